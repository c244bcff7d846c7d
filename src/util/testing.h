#pragma once

// Helpers shared by the unit tests.

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "util/error.h"

namespace mr {

namespace internal {

// The folder under which a test process keeps its files,
// <tmp>/mr_tests_<pid>. It goes when the process exits, unless a test failed
// or MR_KEEP_TEST_FILES is set (not "0"): then its path is printed, for the
// files to be read. Constructed on first use, after GoogleTest's UnitTest,
// so it is destroyed before it.
class TestScratch {
 public:
  TestScratch()
      : root_(std::filesystem::temp_directory_path() /
              ("mr_tests_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(root_);
    std::filesystem::create_directories(root_);
  }
  ~TestScratch() {
    const char* keep = std::getenv("MR_KEEP_TEST_FILES");
    if (::testing::UnitTest::GetInstance()->Failed() ||
        (keep != nullptr && *keep != '\0' && std::string(keep) != "0")) {
      std::fprintf(stderr, "Test files kept in %s\n", root_.c_str());
      return;
    }
    std::error_code ec;
    std::filesystem::remove_all(root_, ec);
  }
  TestScratch(const TestScratch&) = delete;
  TestScratch& operator=(const TestScratch&) = delete;
  const std::filesystem::path& root() const { return root_; }

 private:
  std::filesystem::path root_;
};

inline const std::filesystem::path& TestScratchRoot() {
  static TestScratch scratch;
  return scratch.root();
}

}  // namespace internal

// This test process's scratch folder (created on first use).
inline std::string TestScratchDir() { return internal::TestScratchRoot().string(); }

// A path named `name` in this test process's scratch folder, with nothing
// at it (whatever was there is removed). The scratch folder is removed when
// the process exits, unless a test failed or MR_KEEP_TEST_FILES=1.
inline std::string FreshTestPath(const std::string& name) {
  const auto path = internal::TestScratchRoot() / name;
  std::filesystem::remove_all(path);
  return path.string();
}

// A fresh, empty folder named `name` in the scratch folder.
inline std::string MakeTestDir(const std::string& name) {
  const std::string dir = FreshTestPath(name);
  std::filesystem::create_directories(dir);
  return dir;
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
