#include "util/program.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cstdio>
#include <exception>

#include "util/error.h"

namespace mr {

void KeepFreedBuffersInProcess() {
#if defined(__GLIBC__)
  // The image-space work (pair terms, similarity maps, renders) allocates
  // and frees buffers of a few MB at a high rate. By default glibc serves
  // each from a fresh mmap and unmaps it on free, so every pair pays the
  // page faults of touching its buffers again: that made the first pair
  // terms of the example 3-4x slower than the arithmetic (initial
  // similarity 9 s -> 5 s with this). Blocks up to 32 MB now come from the
  // heap and are reused (32 MB is glibc's largest threshold); up to 512 MB of
  // free heap is kept before trimming.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
#endif
}

int RunProgram(const std::function<int()>& body) {
  KeepFreedBuffersInProcess();
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
