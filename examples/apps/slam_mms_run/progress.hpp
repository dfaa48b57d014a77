#pragma once
// Progress output of slam_mms_run: on a terminal a one-line bar redrawn in place (scans done,
// scans/s, ETA), otherwise plain lines every ~10 %. Log messages (stderr) clear the bar first, so
// warnings stay readable; InstallLogSink routes the library's log through here.
//
// Thread safety: Update/Finish from one thread; the log sink may be called from any thread (the
// library's log mutex serialises it).

#include <chrono>
#include <cstddef>
#include <string>

#include "slam_mms/core/logging.hpp"

namespace slam_mms::app {

class ProgressReporter {
 public:
  /// `label` prefixes every line ("full"); `total` scans expected; `tty`: redraw in place.
  ProgressReporter(std::string label, size_t total, bool tty);
  ~ProgressReporter();
  ProgressReporter(const ProgressReporter&) = delete;
  ProgressReporter& operator=(const ProgressReporter&) = delete;

  void Update(size_t done);
  /// Prints the final line (done scans, total time, mean rate).
  void Finish(size_t done, const std::string& note = "");

  /// Called by the log sink before a message is printed: ends the in-place line.
  static void BreakLine();

 private:
  void Print(size_t done, bool final_line, const std::string& note);

  std::string label_;
  size_t total_;
  bool tty_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  int last_decile_ = -1;
};

/// True when stdout is a terminal.
bool StdoutIsTerminal();

/// Installs a log sink printing "[level] message" to stderr that first breaks a progress bar.
/// Returns the sink it replaced.
LogSink InstallLogSink();

/// "1:05" style duration.
std::string FormatDuration(double seconds);

}  // namespace slam_mms::app
