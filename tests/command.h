#pragma once

// Runs a shell command as a user would, for the end-to-end tests.

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "util/file.h"

namespace mr {

struct CommandResult {
  int exit_code = 0;
  std::string output;  // stdout and stderr together
};

inline CommandResult RunCommand(const std::string& command) {
  const std::string log = (std::filesystem::temp_directory_path() /
                           ("mr_command_" + std::to_string(::getpid()) + ".log"))
                              .string();
  const int status = std::system((command + " > " + log + " 2>&1").c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.output = ReadFileToString(log);
  std::filesystem::remove(log);
  return result;
}

}  // namespace mr
