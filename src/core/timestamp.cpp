#include "slam_mms/core/timestamp.hpp"

#include <cmath>
#include <cstdio>
#include <ctime>

namespace slam_mms {

Timestamp Timestamp::FromSeconds(double seconds) {
  const double whole = std::floor(seconds);
  const auto ns = static_cast<int64_t>(whole) * 1000000000LL +
                  static_cast<int64_t>(std::llround((seconds - whole) * 1e9));
  return Timestamp(ns);
}

Timestamp Timestamp::PlusSeconds(double dt) const {
  return Timestamp(ns_ + static_cast<int64_t>(std::llround(dt * 1e9)));
}

std::string Timestamp::ToKittiString() const {
  int64_t sec = ns_ / 1000000000LL;
  int64_t frac = ns_ % 1000000000LL;
  if (frac < 0) {
    frac += 1000000000LL;
    sec -= 1;
  }
  const std::time_t t = static_cast<std::time_t>(sec);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%04d-%02d-%02d %02d:%02d:%02d.%09lld", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<long long>(frac));
  return buf;
}

}  // namespace slam_mms
