#pragma once
// Test helper: collects the library's log messages while alive (restores the previous sink).
#include <mutex>
#include <string>

#include "slam_mms/core/logging.hpp"

namespace slam_mms::testing {

class LogCapture {
 public:
  LogCapture() {
    previous_ = SetLogSink([this](LogLevel, const std::string& m) {
      std::lock_guard<std::mutex> lock(mu_);
      messages_ += m + "\n";
    });
  }
  ~LogCapture() { SetLogSink(previous_); }
  LogCapture(const LogCapture&) = delete;
  LogCapture& operator=(const LogCapture&) = delete;
  std::string messages() {
    std::lock_guard<std::mutex> lock(mu_);
    return messages_;
  }

 private:
  LogSink previous_;
  std::mutex mu_;
  std::string messages_;
};

}  // namespace slam_mms::testing
