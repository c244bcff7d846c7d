#pragma once

// Helpers shared by the unit tests.

#include <filesystem>
#include <string>

namespace mr {

// A fresh, empty folder under the system's temporary directory, named after
// `name` (an existing one is emptied first).
inline std::string MakeTestDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("mr_test_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace mr
