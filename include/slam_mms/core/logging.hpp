#pragma once
// Logging through a sink the caller installs. The library never prints: without a sink, messages
// are dropped. Apps install a sink that writes to stderr.
//
// Thread safety: SetLogSink/Log may be called from any thread; the sink itself is called under a
// mutex, so it need not be thread-safe.

#include <functional>
#include <sstream>
#include <string>
#include <string_view>

namespace slam_mms {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarning = 2, kError = 3 };

const char* LogLevelName(LogLevel level);
/// The level of one of LogLevelName's names ("debug", "info", "warning", "error"); false for any
/// other (the apps' --log-level).
bool ParseLogLevel(std::string_view name, LogLevel* level);

/// The sink: receives the level and one formatted message (no trailing newline).
using LogSink = std::function<void(LogLevel level, const std::string& message)>;

/// Installs `sink` for the whole process (pass nullptr to drop messages); returns the previous one.
LogSink SetLogSink(LogSink sink);

/// Messages below this level are not formatted nor passed on. Default kInfo.
void SetMinLogLevel(LogLevel level);
LogLevel MinLogLevel();

/// Sends one message to the installed sink (no-op without one).
void Log(LogLevel level, const std::string& message);

/// A sink writing "[level] message" lines to stderr, for apps and tests.
LogSink StderrLogSink();

namespace internal {
class LogMessage {
 public:
  explicit LogMessage(LogLevel level) : level_(level) {}
  ~LogMessage() { Log(level_, stream_.str()); }
  std::ostringstream& stream() { return stream_; }

 private:
  LogLevel level_;
  std::ostringstream stream_;
};
}  // namespace internal

}  // namespace slam_mms

/// `SLAM_MMS_LOG(kWarning) << "skipping " << file;`
#define SLAM_MMS_LOG(level)                                      \
  if (::slam_mms::LogLevel::level < ::slam_mms::MinLogLevel()) { \
  } else                                                         \
    ::slam_mms::internal::LogMessage(::slam_mms::LogLevel::level).stream()
