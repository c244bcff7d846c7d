#pragma once

// Running a piece of third-party code in a child process, so that a crash in
// it (a segmentation fault on input it mishandles) is reported to the caller
// instead of ending the program with the user's work. POSIX only (fork).

#include <functional>
#include <string>

namespace mr {

struct IsolatedResult {
  // kDone: `work` returned and `payload` holds what it returned. kCrashed: the
  // child ended without an answer (killed by `signal`, or exited early).
  enum class Status { kDone, kCrashed };
  Status status = Status::kCrashed;
  std::string payload;
  int signal = 0;
};

// Runs `work` in a forked child and returns its result. An InputError or
// InternalError `work` throws is thrown again here, with its message; any
// other exception becomes an InternalError. The child shares nothing with
// the caller afterwards: `work` must return everything it produces, and
// must not use threads or locks that other threads of the caller may hold
// (the child has only the calling thread). When the process cannot fork,
// `work` runs in the calling process.
IsolatedResult RunIsolated(const std::function<std::string()>& work);

}  // namespace mr
