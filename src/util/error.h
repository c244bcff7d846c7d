#pragma once

// Errors. Bad input (a user's file, flag or workspace) throws InputError with
// the file, the value and what was expected; broken internal invariants throw
// via MR_CHECK. The command-line layer catches both, prints one line and
// exits non-zero.

#include <sstream>
#include <stdexcept>
#include <string>

namespace mr {

// Bad input from outside the program: files, flags, workspaces.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

// A broken internal invariant (a bug, not bad input).
class InternalError : public std::logic_error {
 public:
  explicit InternalError(const std::string& what) : std::logic_error(what) {}
};

namespace internal {

// Collects a message with operator<< and throws it from its destructor.
template <typename E>
class Thrower {
 public:
  Thrower(const char* file, int line, const char* cond) {
    if (cond != nullptr) {
      stream_ << file << ":" << line << " Check failed: " << cond << " ";
    }
  }
  [[noreturn]] ~Thrower() noexcept(false) { throw E(stream_.str()); }
  template <typename T>
  Thrower& operator<<(const T& value) {
    stream_ << value;
    return *this;
  }

 private:
  std::ostringstream stream_;
};

}  // namespace internal
}  // namespace mr

// MR_CHECK(cond) << "context";  throws mr::InternalError when cond is false.
#define MR_CHECK(cond)   \
  if (cond) {            \
  } else                 \
    ::mr::internal::Thrower<::mr::InternalError>(__FILE__, __LINE__, #cond)

#define MR_CHECK_EQ(a, b) MR_CHECK((a) == (b)) << (a) << " vs " << (b) << " "
#define MR_CHECK_LT(a, b) MR_CHECK((a) < (b)) << (a) << " vs " << (b) << " "
#define MR_CHECK_LE(a, b) MR_CHECK((a) <= (b)) << (a) << " vs " << (b) << " "
#define MR_CHECK_GT(a, b) MR_CHECK((a) > (b)) << (a) << " vs " << (b) << " "
#define MR_CHECK_GE(a, b) MR_CHECK((a) >= (b)) << (a) << " vs " << (b) << " "

// MR_THROW_INPUT << "file: what was wrong";  throws mr::InputError.
#define MR_THROW_INPUT ::mr::internal::Thrower<::mr::InputError>(nullptr, 0, nullptr)
