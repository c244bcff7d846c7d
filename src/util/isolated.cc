#include "util/isolated.h"

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <exception>
#include <utility>

#include <sys/wait.h>
#include <unistd.h>

#include "util/error.h"

namespace mr {
namespace {

// What the child sends: one tag byte, the payload's length (8 bytes) and
// the payload (the result, or an exception's message).
enum Tag : char { kResult = 'R', kInputError = 'I', kInternalError = 'X' };

bool WriteAll(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

// Reads until end of file.
std::string ReadAll(int fd) {
  std::string out;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    out.append(buffer, static_cast<size_t>(n));
  }
  return out;
}

[[noreturn]] void AnswerAndExit(int fd, Tag tag, const std::string& payload) {
  const uint64_t size = payload.size();
  const bool sent = WriteAll(fd, reinterpret_cast<const char*>(&tag), 1) &&
                    WriteAll(fd, reinterpret_cast<const char*>(&size), sizeof size) &&
                    WriteAll(fd, payload.data(), payload.size());
  close(fd);
  _exit(sent ? 0 : 1);  // no atexit handlers or destructors: they belong to the parent
}

}  // namespace

IsolatedResult RunIsolated(const std::function<std::string()>& work) {
  IsolatedResult result;
  int fds[2] = {-1, -1};
  const pid_t pid = pipe(fds) == 0 ? fork() : -1;
  if (pid < 0) {  // no pipe or no process to spare: run here
    if (fds[0] >= 0) {
      close(fds[0]);
      close(fds[1]);
    }
    result.payload = work();
    result.status = IsolatedResult::Status::kDone;
    return result;
  }
  if (pid == 0) {
    close(fds[0]);
    try {
      AnswerAndExit(fds[1], kResult, work());
    } catch (const InputError& e) {
      AnswerAndExit(fds[1], kInputError, e.what());
    } catch (const std::exception& e) {
      AnswerAndExit(fds[1], kInternalError, e.what());
    } catch (...) {
      AnswerAndExit(fds[1], kInternalError, "unknown exception");
    }
  }
  close(fds[1]);
  const std::string answer = ReadAll(fds[0]);  // before waiting: the pipe holds only 64 KB
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  uint64_t size = 0;
  if (answer.size() < 1 + sizeof size) return result;  // crashed before answering
  std::memcpy(&size, answer.data() + 1, sizeof size);
  if (answer.size() != 1 + sizeof size + size) return result;
  std::string payload = answer.substr(1 + sizeof size);
  switch (answer[0]) {
    case kResult:
      result.status = IsolatedResult::Status::kDone;
      result.payload = std::move(payload);
      return result;
    case kInputError:
      throw InputError(payload);
    default:
      throw InternalError(payload);
  }
}

}  // namespace mr
