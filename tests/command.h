#pragma once

// Runs a shell command as a user would, for the end-to-end tests.

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "util/file.h"

namespace mr {

struct CommandResult {
  int exit_code = 0;
  std::string output;  // stdout and stderr together
};

// Runs `command` through the shell, stdout and stderr captured. After
// `timeout_s` seconds the command's whole process group is killed (coreutils
// `timeout`) and the output so far returned with a note, so that a blocked
// program fails its test with its log rather than at CTest's timeout with
// nothing to read.
inline CommandResult RunCommand(const std::string& command, int timeout_s = 450) {
  const std::string log = (std::filesystem::temp_directory_path() /
                           ("mr_command_" + std::to_string(::getpid()) + ".log"))
                              .string();
  std::string quoted = "'";
  for (char c : command) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  quoted += "'";
  const std::string wrapped =
      "timeout -k 10 " + std::to_string(timeout_s) + " sh -c " + quoted + " > " + log + " 2>&1";
  const int status = std::system(wrapped.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.output = ReadFileToString(log);
  if (result.exit_code == 124 || result.exit_code == 137) {
    result.output += "\n[RunCommand: killed after " + std::to_string(timeout_s) + " s: " +
                     command + "]\n";
  }
  std::filesystem::remove(log);
  return result;
}

// Starts `args` (args[0]: the executable) in a child process with stdout and
// stderr appended to `log`, and SIGINT and SIGTERM at their default
// dispositions (whatever the test runner set). Returns the child's pid.
inline pid_t SpawnCommand(const std::vector<std::string>& args, const std::string& log) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  ::signal(SIGINT, SIG_DFL);
  ::signal(SIGTERM, SIG_DFL);
  sigset_t none;
  sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (fd < 0) ::_exit(126);
  ::dup2(fd, 1);
  ::dup2(fd, 2);
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  ::execv(argv[0], argv.data());
  ::_exit(127);
}

// Waits up to `timeout_s` for `log` to contain `text` while the child `pid`
// runs. False if the child ended first or the time ran out.
inline bool WaitForLogText(pid_t pid, const std::string& log, const std::string& text,
                           double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    std::error_code ec;
    if (std::filesystem::exists(log, ec) && ReadFileToString(log).find(text) != std::string::npos) {
      return true;
    }
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

// Waits for the child `pid` to end; its exit status, or -signal if a signal
// killed it.
inline int WaitForExit(pid_t pid) {
  int status = 0;
  if (::waitpid(pid, &status, 0) != pid) return -1000;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

}  // namespace mr
