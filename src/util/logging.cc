#include "util/logging.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>

namespace mr {
namespace {

std::atomic<int> g_level{static_cast<int>(LogLevel::kInfo)};
const auto g_start = std::chrono::steady_clock::now();
std::mutex g_mutex;

const char* LevelTag(LogLevel level) {
  switch (level) {
    case LogLevel::kError:
      return "E";
    case LogLevel::kWarning:
      return "W";
    case LogLevel::kInfo:
      return "I";
    case LogLevel::kVerbose:
      return "V";
  }
  return "?";
}

}  // namespace

void SetLogLevel(LogLevel level) { g_level = static_cast<int>(level); }
LogLevel GetLogLevel() { return static_cast<LogLevel>(g_level.load()); }
bool LogEnabled(LogLevel level) { return static_cast<int>(level) <= g_level.load(); }

double ElapsedSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - g_start).count();
}

LogMessage::LogMessage(LogLevel level) : level_(level) {}

LogMessage::~LogMessage() {
  std::lock_guard<std::mutex> lock(g_mutex);
  std::fprintf(stderr, "%s %8.2fs] %s\n", LevelTag(level_), ElapsedSeconds(),
               stream_.str().c_str());
  std::fflush(stderr);
}

Progress::Progress(std::string label, long total, double interval_s)
    : label_(std::move(label)),
      total_(total),
      interval_s_(interval_s),
      start_s_(ElapsedSeconds()),
      last_s_(start_s_) {}

void Progress::Update(long done) {
  const double now = ElapsedSeconds();
  if (now - last_s_ < interval_s_) return;
  last_s_ = now;
  const double pct = total_ > 0 ? 100.0 * done / total_ : 0.0;
  MR_LOG(INFO) << label_ << ": " << done << "/" << total_ << " (" << static_cast<int>(pct)
               << "%, " << now - start_s_ << " s)";
}

void Progress::Done() {
  if (done_) return;
  done_ = true;
  MR_LOG(VERBOSE) << label_ << ": done in " << ElapsedSeconds() - start_s_ << " s";
}

}  // namespace mr
