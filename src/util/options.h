#pragma once

// Command-line and .ini options in COLMAP's style.
//
//   OptionManager options("mesh_refiner", "Refines a COLMAP mesh with DCV.");
//   options.AddRequired("workspace_path", &workspace_path, "COLMAP dense workspace");
//   options.Add("Refine.num_iterations", &refine.num_iterations, "outer iterations");
//   options.Parse(argc, argv);   // throws InputError on unknown or malformed flags
//
// Flags are `--name value` or `--name=value`. A name "Section.field" maps to
// the key `field` under `[Section]` in an .ini file given with
// `--config_path FILE` (read first; flags on the command line override it).
// `--write_config FILE` writes the effective options and exits; it refuses
// (InputError) a FILE that resolves to an input: --config_path, the value of
// any "*_path" option that is not an output ("output_*") or a folder, and
// whatever SetInputPaths returns, and one that cannot be written
// (CheckOutputFile). Booleans take
// 1/0/true/false, or no value (meaning true). `-h`/`--help` prints usage.

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace mr {

class OptionManager {
 public:
  OptionManager(std::string program, std::string description);

  void Add(const std::string& name, bool* value, const std::string& help);
  void Add(const std::string& name, int* value, const std::string& help);
  void Add(const std::string& name, double* value, const std::string& help);
  void Add(const std::string& name, std::string* value, const std::string& help);
  // Required options must be set on the command line or in the config file.
  void AddRequired(const std::string& name, std::string* value, const std::string& help);

  // Parses argv. Returns false if the program should exit 0 without running
  // (after --help or --write_config). Throws InputError on bad flags.
  bool Parse(int argc, char** argv);

  // Reads an .ini file (sections map to "Section." prefixes). Throws InputError.
  void ReadConfig(const std::string& path);
  // The same from the file's text; `path` only names it in errors.
  void ReadConfigData(const std::string& path, const std::string& text);
  // Writes all options as an .ini file (atomically).
  void WriteConfig(const std::string& path) const;
  std::string Usage() const;

  // True if the option was given on the command line or in a config file.
  bool WasSet(const std::string& name) const;

  // The files and folders (whose whole content is input) that the program
  // reads, computed from the parsed options; --write_config may not resolve
  // to or into any of them. Called by Parse after the options are set.
  void SetInputPaths(std::function<std::vector<std::string>()> inputs);

 private:
  struct Entry {
    std::string help;
    std::string type;
    bool required = false;
    bool is_bool = false;
    bool set = false;
    std::function<void(const std::string&)> parse;
    std::function<std::string()> print;
  };
  void Set(const std::string& name, const std::string& value, const std::string& origin);
  Entry& AddEntry(const std::string& name, const std::string& help);

  std::string program_;
  std::string description_;
  std::vector<std::string> order_;
  std::map<std::string, Entry> entries_;
  std::function<std::vector<std::string>()> input_paths_;
};

}  // namespace mr
