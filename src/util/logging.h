#pragma once

// Minimal logging: one line per message on stderr, with elapsed seconds.
//   MR_LOG(INFO) << "Loaded " << n << " images";
//   MR_LOG(VERBOSE) << ...;   printed only when SetLogLevel(LogLevel::kVerbose)

#include <sstream>
#include <string>

namespace mr {

enum class LogLevel { kError = 0, kWarning = 1, kInfo = 2, kVerbose = 3 };

void SetLogLevel(LogLevel level);
LogLevel GetLogLevel();
bool LogEnabled(LogLevel level);

class LogMessage {
 public:
  explicit LogMessage(LogLevel level);
  ~LogMessage();
  template <typename T>
  LogMessage& operator<<(const T& value) {
    stream_ << value;
    return *this;
  }

 private:
  LogLevel level_;
  std::ostringstream stream_;
};

// A progress indicator for long loops: prints "label: k/n (p%)" at most every
// `interval_s` seconds, and a final line when Done() is called.
class Progress {
 public:
  Progress(std::string label, long total, double interval_s = 2.0);
  void Update(long done);
  void Done();

 private:
  std::string label_;
  long total_;
  double interval_s_;
  double start_s_;
  double last_s_;
  bool done_ = false;
};

// Seconds since program start (steady clock).
double ElapsedSeconds();

}  // namespace mr

#define MR_LOG_ERROR ::mr::LogLevel::kError
#define MR_LOG_WARNING ::mr::LogLevel::kWarning
#define MR_LOG_INFO ::mr::LogLevel::kInfo
#define MR_LOG_VERBOSE ::mr::LogLevel::kVerbose
#define MR_LOG(level)                         \
  if (!::mr::LogEnabled(MR_LOG_##level)) {    \
  } else                                      \
    ::mr::LogMessage(MR_LOG_##level)
