#include "util/file.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "util/error.h"

namespace mr {
namespace fs = std::filesystem;

bool ExistsFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

bool ExistsDir(const std::string& path) {
  std::error_code ec;
  return fs::is_directory(path, ec);
}

std::string JoinPaths(const std::string& a, const std::string& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  return (fs::path(a) / fs::path(b)).string();
}

std::string GetParentDir(const std::string& path) {
  return fs::path(path).parent_path().string();
}

std::string GetFileName(const std::string& path) { return fs::path(path).filename().string(); }

std::string GetExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

void CreateDirIfNotExists(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return;
  fs::create_directories(path, ec);
  if (ec) MR_THROW_INPUT << path << ": cannot create directory: " << ec.message();
}

std::vector<std::string> ListFiles(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.is_regular_file()) names.push_back(entry.path().filename().string());
  }
  if (ec) MR_THROW_INPUT << dir << ": cannot list directory: " << ec.message();
  std::sort(names.begin(), names.end());
  return names;
}

std::string ReadFileToString(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) MR_THROW_INPUT << path << ": cannot open file for reading";
  std::ostringstream buffer;
  buffer << file.rdbuf();
  return buffer.str();
}

std::vector<std::string> ReadNameList(const std::string& path) {
  std::vector<std::string> names;
  std::istringstream in(ReadFileToString(path));
  std::string line;
  while (std::getline(in, line)) {
    const auto begin = line.find_first_not_of(" \t\r");
    if (begin == std::string::npos || line[begin] == '#') continue;
    names.push_back(line.substr(begin, line.find_last_not_of(" \t\r") - begin + 1));
  }
  return names;
}

namespace {

// Absolute, normalized, with the symbolic links of its existing part
// resolved and no trailing separator.
fs::path Resolve(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  if (ec) p = fs::absolute(path).lexically_normal();
  if (p.filename().empty() && p.has_parent_path()) p = p.parent_path();
  return p;
}

bool IsInside(const fs::path& path, const fs::path& dir) {
  auto p = path.begin();
  for (auto d = dir.begin(); d != dir.end(); ++d, ++p) {
    if (p == path.end() || *p != *d) return false;
  }
  return p != path.end();
}

}  // namespace

void RefuseOutputOverInput(const std::string& what, const std::string& output,
                           const std::vector<std::string>& inputs) {
  if (output.empty()) return;
  const fs::path out = Resolve(output);
  for (const std::string& input : inputs) {
    if (input.empty()) continue;
    const fs::path in = Resolve(input);
    std::error_code ec;
    if (out == in || fs::equivalent(output, input, ec)) {
      MR_THROW_INPUT << what << " " << output << ": is the input " << input
                     << "; refusing to overwrite an input";
    }
    if (fs::is_directory(in, ec) && IsInside(out, in)) {
      MR_THROW_INPUT << what << " " << output << ": is inside the input folder " << input
                     << "; refusing to overwrite inputs";
    }
  }
}

void WriteFileAtomically(const std::string& path,
                         const std::function<void(std::ostream&)>& write) {
  const fs::path target(path);
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  if (!fs::is_directory(dir)) {
    MR_THROW_INPUT << path << ": output folder " << dir.string() << " does not exist";
  }
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) MR_THROW_INPUT << tmp << ": cannot open for writing";
      write(out);
      out.flush();
      if (!out) MR_THROW_INPUT << tmp << ": write failed (disk full?)";
    }
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) MR_THROW_INPUT << path << ": cannot rename temporary file into place: " << ec.message();
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

}  // namespace mr
