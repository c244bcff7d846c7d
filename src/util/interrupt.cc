#include "util/interrupt.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cstring>

#include "util/logging.h"

namespace mr {
namespace {

// One slot per live temporary. A slot is kFree, kFilling while its path is
// copied in (the handler skips it), or kActive (the handler unlinks it).
enum SlotState : int { kFree = 0, kFilling = 1, kActive = 2 };

struct Slot {
  std::atomic<int> state{kFree};
  char path[TemporaryFileRegistration::kMaxTemporaryPath];
};

Slot g_slots[TemporaryFileRegistration::kMaxTemporaryFiles];
static_assert(std::atomic<int>::is_always_lock_free, "the handler reads the slots' states");

// Async-signal-safe: only unlink, write and _exit.
void HandleInterrupt(int signal_number) {
  for (Slot& slot : g_slots) {
    if (slot.state.load(std::memory_order_acquire) == kActive) ::unlink(slot.path);
  }
  static const char kInt[] = "ERROR: interrupted by SIGINT; unfinished output files removed\n";
  static const char kTerm[] = "ERROR: interrupted by SIGTERM; unfinished output files removed\n";
  const bool is_int = signal_number == SIGINT;
  const ssize_t ignored = ::write(STDERR_FILENO, is_int ? kInt : kTerm,
                                  (is_int ? sizeof(kInt) : sizeof(kTerm)) - 1);
  (void)ignored;
  ::_exit(128 + signal_number);
}

}  // namespace

void InstallInterruptHandlers() {
  for (const int signal_number : {SIGINT, SIGTERM}) {
    struct sigaction previous;
    if (::sigaction(signal_number, nullptr, &previous) != 0) continue;
    if (previous.sa_handler == SIG_IGN) continue;  // nohup, background jobs
    struct sigaction action;
    std::memset(&action, 0, sizeof(action));
    action.sa_handler = HandleInterrupt;
    sigemptyset(&action.sa_mask);
    sigaddset(&action.sa_mask, SIGINT);  // one handler at a time
    sigaddset(&action.sa_mask, SIGTERM);
    ::sigaction(signal_number, &action, nullptr);
  }
}

TemporaryFileRegistration::TemporaryFileRegistration(const std::string& path) {
  if (path.size() >= static_cast<size_t>(kMaxTemporaryPath)) {
    MR_LOG(WARNING) << "temporary file path too long to be removed on interrupt: " << path;
    return;
  }
  for (int i = 0; i < kMaxTemporaryFiles; ++i) {
    int expected = kFree;
    if (g_slots[i].state.compare_exchange_strong(expected, kFilling,
                                                 std::memory_order_acq_rel)) {
      std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
      g_slots[i].state.store(kActive, std::memory_order_release);
      slot_ = i;
      return;
    }
  }
  MR_LOG(WARNING) << "more than " << kMaxTemporaryFiles << " temporary files at once; " << path
                  << " is not removed on interrupt";
}

TemporaryFileRegistration::~TemporaryFileRegistration() {
  if (slot_ >= 0) g_slots[slot_].state.store(kFree, std::memory_order_release);
}

}  // namespace mr
