#include "slam_mms/io/kitti_timestamp.hpp"

#include <cctype>
#include <cstdint>

namespace slam_mms {
namespace {

// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's days_from_civil).
int64_t DaysFromCivil(int64_t y, int64_t m, int64_t d) {
  y -= m <= 2 ? 1 : 0;
  const int64_t era = (y >= 0 ? y : y - 399) / 400;
  const int64_t yoe = y - era * 400;
  const int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

bool IsLeap(int64_t y) { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }

int DaysInMonth(int64_t y, int64_t m) {
  static constexpr int kDays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return m == 2 && IsLeap(y) ? 29 : kDays[m - 1];
}

// Reads exactly `n` digits at `pos`.
bool ReadDigits(std::string_view s, size_t* pos, int n, int64_t* value) {
  if (*pos + static_cast<size_t>(n) > s.size()) return false;
  int64_t v = 0;
  for (int i = 0; i < n; ++i) {
    const char c = s[*pos + i];
    if (c < '0' || c > '9') return false;
    v = v * 10 + (c - '0');
  }
  *pos += n;
  *value = v;
  return true;
}

}  // namespace

StatusOr<Timestamp> ParseKittiTimestamp(std::string_view text) {
  size_t b = 0;
  size_t e = text.size();
  while (b < e && std::isspace(static_cast<unsigned char>(text[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(text[e - 1]))) --e;
  const std::string_view s = text.substr(b, e - b);
  const auto fail = [&](const std::string& what) -> Status {
    return InvalidArgumentError("bad KITTI timestamp '" + std::string(s) + "': " + what +
                                " (expected 'YYYY-MM-DD hh:mm:ss.fffffffff')");
  };
  if (s.empty()) return fail("empty");
  size_t pos = 0;
  int64_t year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0;
  const auto expect = [&](char c) {
    if (pos < s.size() && s[pos] == c) {
      ++pos;
      return true;
    }
    return false;
  };
  if (!ReadDigits(s, &pos, 4, &year)) return fail("year is not 4 digits");
  if (!expect('-')) return fail("missing '-' after year");
  if (!ReadDigits(s, &pos, 2, &month)) return fail("month is not 2 digits");
  if (!expect('-')) return fail("missing '-' after month");
  if (!ReadDigits(s, &pos, 2, &day)) return fail("day is not 2 digits");
  if (!expect(' ') && !expect('T')) return fail("missing ' ' between date and time");
  if (!ReadDigits(s, &pos, 2, &hour)) return fail("hour is not 2 digits");
  if (!expect(':')) return fail("missing ':' after hour");
  if (!ReadDigits(s, &pos, 2, &minute)) return fail("minute is not 2 digits");
  if (!expect(':')) return fail("missing ':' after minute");
  if (!ReadDigits(s, &pos, 2, &second)) return fail("second is not 2 digits");
  int64_t frac_ns = 0;
  if (pos < s.size()) {
    if (!expect('.')) return fail("unexpected character after seconds");
    int digits = 0;
    while (pos < s.size()) {
      const char c = s[pos];
      if (c < '0' || c > '9') return fail("fraction has a non-digit");
      if (digits == 9) return fail("fraction has more than 9 digits");
      frac_ns = frac_ns * 10 + (c - '0');
      ++digits;
      ++pos;
    }
    if (digits == 0) return fail("empty fraction");
    for (int i = digits; i < 9; ++i) frac_ns *= 10;
  }
  // int64 nanoseconds since 1970 span 1677-09-21 .. 2262-04-11: whole years inside that.
  if (year < 1678 || year > 2261) {
    return fail("year " + std::to_string(year) + " out of 1678..2261 (int64 nanoseconds)");
  }
  if (month < 1 || month > 12) return fail("month " + std::to_string(month) + " out of 1..12");
  if (day < 1 || day > DaysInMonth(year, month)) {
    return fail("day " + std::to_string(day) + " out of 1.." +
                std::to_string(DaysInMonth(year, month)));
  }
  if (hour > 23) return fail("hour " + std::to_string(hour) + " out of 0..23");
  if (minute > 59) return fail("minute " + std::to_string(minute) + " out of 0..59");
  if (second > 60) return fail("second " + std::to_string(second) + " out of 0..60");
  const int64_t days = DaysFromCivil(year, month, day);
  const int64_t secs = days * 86400 + hour * 3600 + minute * 60 + second;
  return Timestamp::FromNanoseconds(secs * 1000000000LL + frac_ns);
}

}  // namespace slam_mms
