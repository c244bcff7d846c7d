#pragma once

// The entry point of every command-line program:
//
//   int main(int argc, char** argv) {
//     return mr::RunProgram([&]() -> int { ... return 0; });
//   }
//
// mr::InputError (bad input: files, flags, workspaces) prints one line
// "ERROR: <what>"; any other exception "ERROR (internal): <what>". Both
// return exit status 1. SIGINT and SIGTERM remove the temporary files of
// unfinished outputs and exit with status 130 / 143 (util/interrupt.h). It
// also sets glibc to reuse freed multi-MB buffers instead of returning them
// to the kernel at once (see program.cc).

#include <cstddef>
#include <functional>

namespace mr {

int RunProgram(const std::function<int()>& body);

// Bytes of heap in use, as glibc counts them (mallinfo2: allocated chunks
// plus mmapped blocks), or 0 where the C library does not say. The
// difference between two calls is what was allocated in between and not
// freed.
size_t HeapBytesInUse();

}  // namespace mr
