#pragma once

// Helpers shared by the unit tests.

#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "util/error.h"

namespace mr {

// A fresh, empty folder under the system's temporary directory, named after
// `name` (an existing one is emptied first).
inline std::string MakeTestDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("mr_test_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

// Expects `fn` to throw mr::InputError whose message contains every string
// in `parts` (a file name, the bad value, what was expected, ...).
template <typename Fn>
void ExpectInputError(Fn fn, const std::vector<std::string>& parts) {
  try {
    fn();
    ADD_FAILURE() << "no InputError thrown";
  } catch (const InputError& e) {
    const std::string what = e.what();
    for (const std::string& p : parts) {
      EXPECT_NE(what.find(p), std::string::npos) << "'" << p << "' not in: " << what;
    }
  }
}

}  // namespace mr
