#include "util/program.h"

#include <cstdio>
#include <exception>

#include "util/error.h"

namespace mr {

int RunProgram(const std::function<int()>& body) {
  try {
    return body();
  } catch (const InputError& e) {
    std::fprintf(stderr, "ERROR: %s\n", e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ERROR (internal): %s\n", e.what());
  }
  return 1;
}

}  // namespace mr
