#pragma once

// What an interrupted program leaves behind: nothing half-written.
//
// InstallInterruptHandlers() (called by RunProgram) makes SIGINT and SIGTERM
// remove every registered temporary file, print one line
//
//   ERROR: interrupted by SIGINT; unfinished output files removed
//
// and exit at once with status 128 + signal (130 for SIGINT, 143 for
// SIGTERM), as a shell reports a process killed by that signal. The handler
// is async-signal-safe: it walks a fixed-size table of paths and calls only
// unlink(2), write(2) and _exit(2). Outputs are only ever written as
// temporaries renamed into place (WriteFileAtomically), so an interrupted run
// leaves existing outputs byte-identical.
//
// A signal that was ignored when the program started (a job started with
// `nohup` or in the background of a non-interactive shell) stays ignored.

#include <string>

namespace mr {

// Installs the SIGINT and SIGTERM handlers described above. Idempotent.
void InstallInterruptHandlers();

// A temporary file that an interrupt removes while this object lives (for
// writers: construct before creating the file, destroy after renaming or
// removing it). Up to kMaxTemporaryFiles live at once, paths up to
// kMaxTemporaryPath - 1 bytes; beyond that a temporary is not registered
// (and would be left behind by an interrupt), which is logged.
class TemporaryFileRegistration {
 public:
  explicit TemporaryFileRegistration(const std::string& path);
  ~TemporaryFileRegistration();
  TemporaryFileRegistration(const TemporaryFileRegistration&) = delete;
  TemporaryFileRegistration& operator=(const TemporaryFileRegistration&) = delete;

  static constexpr int kMaxTemporaryFiles = 64;
  static constexpr int kMaxTemporaryPath = 4096;

 private:
  int slot_ = -1;
};

}  // namespace mr
