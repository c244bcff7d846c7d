#pragma once

// Shared by the libFuzzer harnesses (see docs/fuzzing.md).
//
// A reader that refuses bad input by throwing is correct: the harnesses catch
// std::exception. Only crashes, sanitizer reports, timeouts, out-of-memory and
// exceptions not derived from std::exception are findings. With the
// environment variable MR_FUZZ_STRICT=1, an exception other than
// mr::InputError (an MR_CHECK's InternalError, std::bad_alloc, std::out_of_range
// from the standard library, ...) aborts too: bad input should be refused with
// an InputError that names the file, and anything else is worth a look.
// MR_FUZZ_PRINT=1 prints every refusal (to check what a seed reaches).

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>

#include "util/error.h"

namespace mr {
namespace fuzz {

inline bool EnvFlag(const char* name) {
  const char* s = std::getenv(name);
  return s != nullptr && s[0] != '\0' && std::strcmp(s, "0") != 0;
}

inline bool Strict() {
  static const bool strict = EnvFlag("MR_FUZZ_STRICT");
  return strict;
}

inline bool Print() {
  static const bool print = EnvFlag("MR_FUZZ_PRINT");
  return print;
}

// Runs `read` on the input; returns 0 as libFuzzer expects.
template <typename Fn>
int Run(Fn read) {
  try {
    read();
  } catch (const InputError& e) {
    if (Print()) std::fprintf(stderr, "refused: %s\n", e.what());
  } catch (const std::exception& e) {
    if (Print()) std::fprintf(stderr, "refused (not an InputError): %s\n", e.what());
    if (Strict()) {
      std::fprintf(stderr, "MR_FUZZ_STRICT: exception other than mr::InputError: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}

inline std::string Bytes(const uint8_t* data, size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

}  // namespace fuzz
}  // namespace mr
