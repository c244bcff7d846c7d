#include "util/options.h"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>

#include "util/error.h"
#include "util/file.h"

namespace mr {
namespace {

std::string Trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return "";
  const auto end = s.find_last_not_of(" \t\r\n");
  return s.substr(begin, end - begin + 1);
}

bool ParseBool(const std::string& text, bool* value) {
  if (text == "1" || text == "true" || text == "True" || text == "TRUE") {
    *value = true;
    return true;
  }
  if (text == "0" || text == "false" || text == "False" || text == "FALSE") {
    *value = false;
    return true;
  }
  return false;
}

std::string FormatDouble(double v) {
  std::ostringstream s;
  s << std::setprecision(std::numeric_limits<double>::max_digits10 - 2) << v;
  return s.str();
}

}  // namespace

OptionManager::OptionManager(std::string program, std::string description)
    : program_(std::move(program)), description_(std::move(description)) {}

OptionManager::Entry& OptionManager::AddEntry(const std::string& name, const std::string& help) {
  MR_CHECK(entries_.count(name) == 0) << "option registered twice: " << name;
  order_.push_back(name);
  Entry& e = entries_[name];
  e.help = help;
  return e;
}

void OptionManager::Add(const std::string& name, bool* value, const std::string& help) {
  Entry& e = AddEntry(name, help);
  e.type = "bool";
  e.is_bool = true;
  e.parse = [name, value](const std::string& text) {
    if (!ParseBool(text, value)) {
      MR_THROW_INPUT << "--" << name << " " << text << ": expected 1/0/true/false";
    }
  };
  e.print = [value] { return std::string(*value ? "1" : "0"); };
}

void OptionManager::Add(const std::string& name, int* value, const std::string& help) {
  Entry& e = AddEntry(name, help);
  e.type = "int";
  e.parse = [name, value](const std::string& text) {
    try {
      size_t pos = 0;
      const long v = std::stol(text, &pos);
      if (pos != text.size() || v < std::numeric_limits<int>::min() ||
          v > std::numeric_limits<int>::max()) {
        throw std::invalid_argument(text);
      }
      *value = static_cast<int>(v);
    } catch (const std::exception&) {
      MR_THROW_INPUT << "--" << name << " " << text << ": expected an integer";
    }
  };
  e.print = [value] { return std::to_string(*value); };
}

void OptionManager::Add(const std::string& name, double* value, const std::string& help) {
  Entry& e = AddEntry(name, help);
  e.type = "double";
  e.parse = [name, value](const std::string& text) {
    try {
      size_t pos = 0;
      const double v = std::stod(text, &pos);
      if (pos != text.size() || !std::isfinite(v)) throw std::invalid_argument(text);
      *value = v;
    } catch (const std::exception&) {
      MR_THROW_INPUT << "--" << name << " " << text << ": expected a finite number";
    }
  };
  e.print = [value] { return FormatDouble(*value); };
}

void OptionManager::Add(const std::string& name, std::string* value, const std::string& help) {
  Entry& e = AddEntry(name, help);
  e.type = "string";
  e.parse = [value](const std::string& text) { *value = text; };
  e.print = [value] { return *value; };
}

void OptionManager::AddRequired(const std::string& name, std::string* value,
                                const std::string& help) {
  Add(name, value, help);
  entries_[name].required = true;
}

bool OptionManager::WasSet(const std::string& name) const {
  const auto it = entries_.find(name);
  return it != entries_.end() && it->second.set;
}

void OptionManager::SetInputPaths(std::function<std::vector<std::string>()> inputs) {
  input_paths_ = std::move(inputs);
}

void OptionManager::Set(const std::string& name, const std::string& value,
                        const std::string& origin) {
  auto it = entries_.find(name);
  if (it == entries_.end()) {
    MR_THROW_INPUT << origin << ": unknown option '" << name << "' (see --help)";
  }
  it->second.parse(value);
  it->second.set = true;
}

void OptionManager::ReadConfig(const std::string& path) {
  ReadConfigData(path, ReadFileToString(path));
}

void OptionManager::ReadConfigData(const std::string& path, const std::string& text) {
  std::istringstream in(text);
  std::string line, section;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    line = Trim(line);
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    if (line.front() == '[') {
      if (line.back() != ']') {
        MR_THROW_INPUT << path << ":" << line_no << ": malformed section header '" << line << "'";
      }
      section = Trim(line.substr(1, line.size() - 2));
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos) {
      MR_THROW_INPUT << path << ":" << line_no << ": expected 'key=value', got '" << line << "'";
    }
    const std::string key = Trim(line.substr(0, eq));
    const std::string value = Trim(line.substr(eq + 1));
    const std::string name = section.empty() ? key : section + "." + key;
    Set(name, value, path + ":" + std::to_string(line_no));
  }
}

void OptionManager::WriteConfig(const std::string& path) const {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << "# " << program_ << " options\n";
    std::string current;
    for (const auto& name : order_) {
      const auto dot = name.find('.');
      const std::string section = dot == std::string::npos ? "" : name.substr(0, dot);
      const std::string key = dot == std::string::npos ? name : name.substr(dot + 1);
      if (section != current) {
        out << "\n[" << section << "]\n";
        current = section;
      }
      out << key << "=" << entries_.at(name).print() << "\n";
    }
  });
}

std::string OptionManager::Usage() const {
  std::ostringstream s;
  s << program_ << ": " << description_ << "\n\nOptions:\n";
  s << "  --config_path FILE   read options from an .ini file first\n";
  s << "  --write_config FILE  write the effective options to FILE and exit\n";
  s << "  -h, --help           print this help\n";
  for (const auto& name : order_) {
    const Entry& e = entries_.at(name);
    s << "  --" << name << " (" << e.type << (e.required ? ", required" : "")
      << ", default: " << (e.print().empty() ? "\"\"" : e.print()) << ")\n      " << e.help
      << "\n";
  }
  return s.str();
}

bool OptionManager::Parse(int argc, char** argv) {
  std::vector<std::pair<std::string, std::string>> flags;
  std::string config_path, write_config;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      std::cout << Usage();
      return false;
    }
    if (arg.rfind("--", 0) != 0) {
      MR_THROW_INPUT << "unexpected argument '" << arg << "': options are --name value (see --help)";
    }
    arg = arg.substr(2);
    std::string value;
    bool has_value = false;
    const auto eq = arg.find('=');
    if (eq != std::string::npos) {
      value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
      has_value = true;
    }
    const auto it = entries_.find(arg);
    const bool is_bool = it != entries_.end() && it->second.is_bool;
    if (!has_value) {
      const bool next_is_value = i + 1 < argc && std::string(argv[i + 1]).rfind("--", 0) != 0;
      bool dummy;
      if (is_bool && (!next_is_value || !ParseBool(argv[i + 1], &dummy))) {
        value = "1";
      } else if (next_is_value) {
        value = argv[++i];
      } else {
        MR_THROW_INPUT << "--" << arg << ": missing value";
      }
    }
    if (arg == "config_path") {
      config_path = value;
    } else if (arg == "write_config") {
      write_config = value;
    } else {
      flags.emplace_back(arg, value);
    }
  }
  if (!config_path.empty()) ReadConfig(config_path);
  for (const auto& [name, value] : flags) Set(name, value, "command line");
  if (!write_config.empty()) {
    std::vector<std::string> inputs = {config_path};
    for (const auto& name : order_) {
      const Entry& e = entries_.at(name);
      const bool is_path = e.type == "string" && name.size() > 5 &&
                           name.compare(name.size() - 5, 5, "_path") == 0;
      if (is_path && name.rfind("output", 0) != 0 && !ExistsDir(e.print())) {
        inputs.push_back(e.print());
      }
    }
    if (input_paths_) {
      for (const std::string& path : input_paths_()) inputs.push_back(path);
    }
    RefuseOutputOverInput("--write_config", write_config, inputs);
    CheckOutputFile("--write_config", write_config);
    WriteConfig(write_config);
    return false;
  }
  for (const auto& name : order_) {
    const Entry& e = entries_.at(name);
    if (e.required && !e.set) MR_THROW_INPUT << "missing required option --" << name;
  }
  return true;
}

}  // namespace mr
