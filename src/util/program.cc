#include "util/program.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cstdio>
#include <exception>

#include "util/error.h"
#include "util/interrupt.h"

namespace mr {
namespace {

void KeepFreedBuffersInProcess() {
#if defined(__GLIBC__)
  // The image-space work (pair terms, similarity maps, renders) and the
  // denoiser's solver allocate and free buffers of megabytes to hundreds of
  // megabytes at a high rate. By default glibc serves each large one from a
  // fresh mmap and unmaps it on free, so every use pays the page faults of
  // touching it again. Measured: the example's initial similarity 9 s -> 5 s;
  // the L_p denoiser on 1M faces 35 s -> 16 s and on 3M faces 134 s -> 47 s
  // (52 s of it in the kernel before). So everything comes from the heap and
  // is reused, and up to 512 MB of free heap is kept before trimming; peak
  // memory is unchanged in those runs.
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
#endif
}

}  // namespace

size_t HeapBytesInUse() {
#if defined(__GLIBC__)
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;
#else
  return 0;
#endif
}

int RunProgram(const std::function<int()>& body) {
  KeepFreedBuffersInProcess();
  InstallInterruptHandlers();
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
