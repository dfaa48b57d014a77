#include "slam_mms_run/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>

#include "slam_mms/core/logging.hpp"

namespace slam_mms::app {
namespace {
// Whether a bar line is open on stdout (a log message must start a new line first).
std::atomic<bool> g_bar_open{false};
}  // namespace

bool StdoutIsTerminal() { return isatty(STDOUT_FILENO) == 1; }

std::string FormatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--:--";
  const long s = std::lround(seconds);
  char buf[32];
  if (s >= 3600) {
    std::snprintf(buf, sizeof(buf), "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  } else {
    std::snprintf(buf, sizeof(buf), "%ld:%02ld", s / 60, s % 60);
  }
  return buf;
}

void ProgressReporter::BreakLine() {
  if (g_bar_open.exchange(false)) {
    std::fputs("\n", stdout);
    std::fflush(stdout);
  }
}

LogSink InstallLogSink() {
  return SetLogSink([](LogLevel level, const std::string& message) {
    ProgressReporter::BreakLine();
    std::fprintf(stderr, "[%s] %s\n", LogLevelName(level), message.c_str());
    std::fflush(stderr);
  });
}

ProgressReporter::ProgressReporter(std::string label, size_t total, bool tty)
    : label_(std::move(label)),
      total_(total),
      tty_(tty),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_ - std::chrono::seconds(1)) {}

ProgressReporter::~ProgressReporter() { BreakLine(); }

void ProgressReporter::Update(size_t done) {
  const auto now = std::chrono::steady_clock::now();
  if (tty_) {
    if (now - last_draw_ < std::chrono::milliseconds(200) && done < total_) return;
    last_draw_ = now;
    Print(done, false, "");
    return;
  }
  const int decile = total_ > 0 ? static_cast<int>(10 * done / total_) : 10;
  if (decile > last_decile_ && decile < 10) {
    last_decile_ = decile;
    Print(done, false, "");
  }
}

void ProgressReporter::Finish(size_t done, const std::string& note) { Print(done, true, note); }

void ProgressReporter::Print(size_t done, bool final_line, const std::string& note) {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  const double eta = rate > 0 && total_ > done ? static_cast<double>(total_ - done) / rate
                                               : (done >= total_ ? 0 : NAN);
  const double fraction = total_ > 0 ? std::min(1.0, static_cast<double>(done) / total_) : 1.0;
  char line[256];
  if (tty_) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::string bar(static_cast<size_t>(filled), '#');
    bar.resize(kWidth, '.');
    if (final_line) {
      std::snprintf(line, sizeof(line), "\r\033[K[%s] [%s] %zu/%zu scans in %s, %.1f scans/s%s%s\n",
                    label_.c_str(), bar.c_str(), done, total_, FormatDuration(elapsed).c_str(),
                    rate, note.empty() ? "" : " ", note.c_str());
      g_bar_open = false;
    } else {
      std::snprintf(line, sizeof(line), "\r\033[K[%s] [%s] %zu/%zu %5.1f%% %.1f scans/s ETA %s",
                    label_.c_str(), bar.c_str(), done, total_, 100.0 * fraction, rate,
                    FormatDuration(eta).c_str());
      g_bar_open = true;
    }
  } else if (final_line) {
    std::snprintf(line, sizeof(line), "[%s] done: %zu/%zu scans in %s, %.1f scans/s%s%s\n",
                  label_.c_str(), done, total_, FormatDuration(elapsed).c_str(), rate,
                  note.empty() ? "" : " ", note.c_str());
  } else {
    std::snprintf(line, sizeof(line), "[%s] %zu/%zu scans (%.0f%%), %.1f scans/s, ETA %s\n",
                  label_.c_str(), done, total_, 100.0 * fraction, rate,
                  FormatDuration(eta).c_str());
  }
  std::fputs(line, stdout);
  std::fflush(stdout);
}

}  // namespace slam_mms::app
