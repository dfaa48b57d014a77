#include "io/nmea.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "io/file_util.hpp"

namespace slam_mms::io_internal {
namespace {

constexpr int64_t kNsPerSecond = 1000000000LL;
constexpr int64_t kNsPerDay = 86400LL * kNsPerSecond;
constexpr int64_t kHalfDayNs = kNsPerDay / 2;

// One sentence with a valid checksum, split at commas (fields[0] = "GPGGA").
struct Sentence {
  int line = 0;
  std::string type;  // "GGA", "GST", "RMC", "ZDA", ... ("" for proprietary/odd addresses)
  std::vector<std::string> fields;
};

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

std::vector<std::string> SplitCommas(std::string_view s) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t c = s.find(',', start);
    if (c == std::string_view::npos) {
      out.emplace_back(s.substr(start));
      return out;
    }
    out.emplace_back(s.substr(start, c - start));
    start = c + 1;
  }
}

// Checks "$...*hh"; on success fills `sentence`, else sets `why`.
bool SplitSentence(std::string_view line, Sentence* sentence, std::string* why) {
  while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) {
    line.remove_suffix(1);
  }
  while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front()))) {
    line.remove_prefix(1);
  }
  if (line.empty() || line[0] != '$') {
    *why = "not an NMEA sentence (no leading '$')";
    return false;
  }
  const size_t star = line.rfind('*');
  if (star == std::string_view::npos || star + 3 != line.size()) {
    *why = "no checksum ('*hh' at the end)";
    return false;
  }
  const int hi = HexValue(line[star + 1]);
  const int lo = HexValue(line[star + 2]);
  if (hi < 0 || lo < 0) {
    *why = "checksum '" + std::string(line.substr(star + 1)) + "' is not two hex digits";
    return false;
  }
  unsigned char sum = 0;
  for (size_t k = 1; k < star; ++k) sum ^= static_cast<unsigned char>(line[k]);
  if (sum != hi * 16 + lo) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "checksum %c%c wrong (computed %02X)", line[star + 1],
                  line[star + 2], sum);
    *why = buf;
    return false;
  }
  sentence->fields = SplitCommas(line.substr(1, star - 1));
  const std::string& address = sentence->fields[0];
  sentence->type = address.size() == 5 && address[0] != 'P' ? address.substr(2) : "";
  return true;
}

bool AllDigits(std::string_view s) {
  if (s.empty()) return false;
  for (const char c : s) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

// "hhmmss[.f{1,9}]" -> nanoseconds of the day.
bool ParseTimeOfDay(const std::string& s, int64_t* ns) {
  if (s.size() < 6 || !AllDigits(std::string_view(s).substr(0, 6))) return false;
  const int64_t h = (s[0] - '0') * 10 + (s[1] - '0');
  const int64_t m = (s[2] - '0') * 10 + (s[3] - '0');
  const int64_t sec = (s[4] - '0') * 10 + (s[5] - '0');
  if (h > 23 || m > 59 || sec > 59) return false;
  int64_t frac = 0;
  if (s.size() > 6) {
    const std::string_view f = std::string_view(s).substr(7);
    if (s[6] != '.' || f.size() > 9 || (!f.empty() && !AllDigits(f))) return false;
    int64_t scale = kNsPerSecond;
    for (const char c : f) {
      scale /= 10;
      frac += (c - '0') * scale;
    }
  }
  *ns = ((h * 60 + m) * 60 + sec) * kNsPerSecond + frac;
  return true;
}

bool ParseNumber(const std::string& s, double* v) { return ParseDouble(s, v); }

// "ddmm.mmmm" (latitude, 2 degree digits) or "dddmm.mmmm" (longitude, 3) with its hemisphere.
bool ParseAngle(const std::string& s, const std::string& hemisphere, int degree_digits,
                char positive, char negative, double* deg) {
  const size_t dot = s.find('.');
  const size_t int_len = dot == std::string::npos ? s.size() : dot;
  if (int_len != static_cast<size_t>(degree_digits) + 2) return false;
  if (!AllDigits(std::string_view(s).substr(0, int_len))) return false;
  if (dot != std::string::npos && !AllDigits(std::string_view(s).substr(dot + 1)) &&
      dot + 1 != s.size()) {
    return false;
  }
  const double d = std::atof(s.substr(0, static_cast<size_t>(degree_digits)).c_str());
  double minutes = 0.0;
  if (!ParseNumber(s.substr(static_cast<size_t>(degree_digits)), &minutes) || minutes >= 60.0) {
    return false;
  }
  const double value = d + minutes / 60.0;
  if (value > (degree_digits == 2 ? 90.0 : 180.0)) return false;
  if (hemisphere.size() != 1 || (hemisphere[0] != positive && hemisphere[0] != negative)) {
    return false;
  }
  *deg = hemisphere[0] == negative ? -value : value;
  return true;
}

bool QualityToType(const std::string& q, GnssFixType* type) {
  if (q.size() != 1 || q[0] < '0' || q[0] > '9') return false;
  switch (q[0]) {
    case '1':
    case '3': *type = GnssFixType::kSingle; break;
    case '2':
    case '9': *type = GnssFixType::kDifferential; break;
    case '4': *type = GnssFixType::kRtkFixed; break;
    case '5': *type = GnssFixType::kRtkFloat; break;
    default: *type = GnssFixType::kNone; break;
  }
  return true;
}

int TypeToQuality(GnssFixType type) {
  switch (type) {
    case GnssFixType::kSingle: return 1;
    case GnssFixType::kDifferential: return 2;
    case GnssFixType::kRtkFixed: return 4;
    case GnssFixType::kRtkFloat: return 5;
    default: return 0;
  }
}

// Date of an RMC (fields[9] ddmmyy) or ZDA (fields[2..4]) sentence.
bool SentenceDate(const Sentence& s, int64_t* days, int64_t* tod_ns) {
  if (s.fields.size() < 2 || !ParseTimeOfDay(s.fields[1], tod_ns)) return false;
  int64_t y = 0, m = 0, d = 0;
  if (s.type == "RMC") {
    if (s.fields.size() < 10 || s.fields[9].size() != 6 || !AllDigits(s.fields[9])) return false;
    const std::string& t = s.fields[9];
    d = std::atoi(t.substr(0, 2).c_str());
    m = std::atoi(t.substr(2, 2).c_str());
    y = std::atoi(t.substr(4, 2).c_str());
    y += y >= 80 ? 1900 : 2000;
  } else {
    if (s.fields.size() < 5 || !AllDigits(s.fields[2]) || !AllDigits(s.fields[3]) ||
        s.fields[4].size() != 4 || !AllDigits(s.fields[4]) || s.fields[2].size() > 2 ||
        s.fields[3].size() > 2) {
      return false;
    }
    d = std::atoi(s.fields[2].c_str());
    m = std::atoi(s.fields[3].c_str());
    y = std::atoi(s.fields[4].c_str());
  }
  // int64 nanoseconds since 1970 end in 2262.
  return y >= 1970 && y <= 2200 && CivilToDays(y, m, d, days);
}

std::string TimeText(int64_t tod_ns) {
  char buf[32];
  const int64_t s = tod_ns / kNsPerSecond;
  std::snprintf(buf, sizeof(buf), "%02lld:%02lld:%02lld.%09lld", static_cast<long long>(s / 3600),
                static_cast<long long>(s / 60 % 60), static_cast<long long>(s % 60),
                static_cast<long long>(tod_ns % kNsPerSecond));
  return buf;
}

struct PendingGst {
  int64_t tod_ns = -1;
  double sigma_h = 0, sigma_v = 0;
};

}  // namespace

bool CivilToDays(int64_t y, int64_t m, int64_t d, int64_t* days) {
  static constexpr int kDays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (m < 1 || m > 12 || d < 1) return false;
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  if (d > (m == 2 && leap ? 29 : kDays[m - 1])) return false;
  // H. Hinnant's days_from_civil.
  y -= m <= 2;
  const int64_t era = (y >= 0 ? y : y - 399) / 400;
  const int64_t yoe = y - era * 400;
  const int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  *days = era * 146097 + doe - 719468;
  return true;
}

void NmeaDefaultSigmas(GnssFixType type, double* h, double* v) {
  switch (type) {
    case GnssFixType::kRtkFixed: *h = 0.02, *v = 0.03; break;
    case GnssFixType::kRtkFloat: *h = 0.5, *v = 0.75; break;
    case GnssFixType::kDifferential: *h = 1.0, *v = 1.5; break;
    case GnssFixType::kSingle: *h = 3.0, *v = 4.5; break;
    default: *h = 10.0, *v = 15.0; break;
  }
}

StatusOr<NmeaGnss> ParseNmeaGnss(std::string_view bytes, const std::string& file,
                                 const NmeaOptions& options) {
  NmeaGnss out;
  const auto note_bad = [&](int line, const std::string& why) {
    ++out.num_bad;
    if (out.bad.size() < NmeaGnss::kMaxListedBad) {
      out.bad.push_back(file + ":" + std::to_string(line) + ": " + why);
    }
  };
  // Pass 1: sentences with valid checksums; the first usable date.
  std::vector<Sentence> sentences;
  const std::vector<std::string> lines = SplitLines(bytes);
  bool have_first_date = false;
  int64_t first_date_days = 0, first_date_tod = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (IsBlank(lines[i])) continue;
    Sentence s;
    s.line = static_cast<int>(i) + 1;
    std::string why;
    if (!SplitSentence(lines[i], &s, &why)) {
      note_bad(s.line, why);
      continue;
    }
    ++out.num_sentences;
    if (s.type == "RMC" || s.type == "ZDA") {
      int64_t days = 0, tod = 0;
      if (!SentenceDate(s, &days, &tod)) {
        note_bad(s.line, s.type + " with a malformed time or date");
        continue;
      }
      if (!have_first_date) {
        have_first_date = true;
        first_date_days = days;
        first_date_tod = tod;
      }
    } else if (s.type != "GGA" && s.type != "GST") {
      ++out.num_ignored;
      continue;
    }
    sentences.push_back(std::move(s));
  }

  // Pass 2: fixes.
  bool have_ref = false;
  int64_t ref_day = 0, ref_tod = 0;  // the date in force and the time of day it was set at
  std::vector<bool> has_gst;
  std::vector<int64_t> fix_tod;
  PendingGst pending;
  for (const Sentence& s : sentences) {
    const std::string where = file + ":" + std::to_string(s.line);
    if (s.type == "RMC" || s.type == "ZDA") {
      SentenceDate(s, &ref_day, &ref_tod);
      have_ref = true;
      continue;
    }
    int64_t tod = 0;
    if (s.fields.size() < 2 || !ParseTimeOfDay(s.fields[1], &tod)) {
      note_bad(s.line, s.type + " with a malformed time of day");
      continue;
    }
    if (s.type == "GST") {
      double lat_sigma = 0, lon_sigma = 0, alt_sigma = 0;
      if (s.fields.size() < 9 || !ParseNumber(s.fields[6], &lat_sigma) ||
          !ParseNumber(s.fields[7], &lon_sigma) || !ParseNumber(s.fields[8], &alt_sigma) ||
          lat_sigma < 0 || lon_sigma < 0 || alt_sigma < 0) {
        note_bad(s.line, "GST without valid latitude/longitude/altitude sigmas (fields 6-8)");
        continue;
      }
      PendingGst g;
      g.tod_ns = tod;
      g.sigma_h = lat_sigma == lon_sigma
                      ? lon_sigma
                      : std::sqrt(0.5 * (lat_sigma * lat_sigma + lon_sigma * lon_sigma));
      g.sigma_v = alt_sigma;
      if (!out.fixes.empty() && fix_tod.back() == tod && !has_gst.back()) {
        out.fixes.back().sigma_horizontal_m = g.sigma_h;
        out.fixes.back().sigma_vertical_m = g.sigma_v;
        has_gst.back() = true;
      } else {
        pending = g;
      }
      continue;
    }
    // GGA.
    if (s.fields.size() < 10) {
      note_bad(s.line, "GGA has " + std::to_string(s.fields.size() - 1) +
                           " fields, expected at least 9 (up to the altitude)");
      continue;
    }
    GnssFix fix;
    if (!QualityToType(s.fields[6], &fix.type)) {
      note_bad(s.line, "GGA field 6 (quality) '" + s.fields[6] + "' is not a digit 0-9");
      continue;
    }
    if (s.fields[2].empty() && s.fields[4].empty() && fix.type == GnssFixType::kNone) {
      ++out.num_without_position;
      continue;
    }
    double alt = 0.0, sep = 0.0;
    if (!ParseAngle(s.fields[2], s.fields[3], 2, 'N', 'S', &fix.latitude_deg)) {
      note_bad(s.line, "GGA fields 2-3 (latitude) '" + s.fields[2] + "," + s.fields[3] +
                           "' malformed (ddmm.mmmm,N|S)");
      continue;
    }
    if (!ParseAngle(s.fields[4], s.fields[5], 3, 'E', 'W', &fix.longitude_deg)) {
      note_bad(s.line, "GGA fields 4-5 (longitude) '" + s.fields[4] + "," + s.fields[5] +
                           "' malformed (dddmm.mmmm,E|W)");
      continue;
    }
    if (!ParseNumber(s.fields[9], &alt)) {
      note_bad(s.line, "GGA field 9 (altitude) '" + s.fields[9] + "' is not a number");
      continue;
    }
    if (s.fields.size() > 11 && !s.fields[11].empty()) {
      if (!ParseNumber(s.fields[11], &sep)) {
        note_bad(s.line, "GGA field 11 (geoid separation) '" + s.fields[11] + "' is not a number");
        continue;
      }
    } else {
      ++out.num_empty_separation;
    }
    if (!s.fields[7].empty()) {
      if (!AllDigits(s.fields[7]) || s.fields[7].size() > 3) {
        note_bad(s.line, "GGA field 7 (satellites) '" + s.fields[7] + "' is not a count");
        continue;
      }
      fix.num_satellites = std::atoi(s.fields[7].c_str());
    }
    fix.height_m = alt + sep;
    // The date.
    int64_t day = 0;
    if (!have_ref) {
      if (have_first_date && std::llabs(first_date_tod - tod) < kNsPerSecond) {
        ref_day = first_date_days;
        ref_tod = first_date_tod;
      } else if (options.utc_date_days.has_value()) {
        ref_day = *options.utc_date_days;
        ref_tod = tod;
      } else {
        return DataLossError(where + ": GGA at " + TimeText(tod) +
                             " comes before any date (no RMC or ZDA sentence of the same epoch "
                             "before it): give the UTC date (FolderDriveReader::Options::"
                             "nmea_utc_date)");
      }
      have_ref = true;
    }
    day = ref_day;
    if (tod + kHalfDayNs < ref_tod) ++day;  // past midnight since the date was set
    if (tod > ref_tod + kHalfDayNs) --day;  // a date sentence just after midnight
    ref_day = day;
    ref_tod = tod;
    fix.stamp = Timestamp::FromNanoseconds(day * kNsPerDay + tod);
    if (!out.fixes.empty() && fix.stamp <= out.fixes.back().stamp) {
      return DataLossError(
          where + ": GGA time " + fix.stamp.ToKittiString() +
          (fix.stamp == out.fixes.back().stamp ? " duplicated" : " goes backwards") + " (line " +
          std::to_string(out.fix_lines.back()) + " has " + out.fixes.back().stamp.ToKittiString() +
          ")");
    }
    const bool gst = pending.tod_ns == tod;
    if (gst) {
      fix.sigma_horizontal_m = pending.sigma_h;
      fix.sigma_vertical_m = pending.sigma_v;
      pending.tod_ns = -1;
    } else {
      NmeaDefaultSigmas(fix.type, &fix.sigma_horizontal_m, &fix.sigma_vertical_m);
    }
    out.fixes.push_back(fix);
    out.fix_lines.push_back(s.line);
    has_gst.push_back(gst);
    fix_tod.push_back(tod);
  }
  for (const bool g : has_gst) out.num_without_gst += g ? 0 : 1;
  return out;
}

std::string NmeaSentence(std::string_view body) {
  unsigned char sum = 0;
  for (const char c : body) sum ^= static_cast<unsigned char>(c);
  char tail[8];
  std::snprintf(tail, sizeof(tail), "*%02X\r\n", sum);
  return "$" + std::string(body) + tail;
}

namespace {

// |deg| as "ddmm.mmmmmmmmm" (degree_digits 2) or "dddmm.mmmmmmmmm", rounded to 1e-9 minutes.
std::string FormatAngle(double deg, int degree_digits) {
  constexpr long long kUnitsPerMinute = 1000000000LL;  // 9 decimals of a minute (1.9 um)
  const long long total = std::llround(std::abs(deg) * 60.0 * kUnitsPerMinute);
  const long long d = total / (60 * kUnitsPerMinute);
  const long long rest = total % (60 * kUnitsPerMinute);
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%0*lld%02lld.%09lld", degree_digits, d, rest / kUnitsPerMinute,
                rest % kUnitsPerMinute);
  return buf;
}

}  // namespace

std::string FormatNmeaEpoch(const GnssFix& fix, int time_decimals) {
  time_decimals = std::max(0, std::min(9, time_decimals));
  int64_t unit = 1;
  for (int k = 0; k < 9 - time_decimals; ++k) unit *= 10;
  // Round the stamp to the written resolution first, so that a carry reaches the date.
  int64_t ns = fix.stamp.nanoseconds();
  const int64_t q = (ns >= 0 ? ns + unit / 2 : ns - unit / 2 + 1) / unit;
  ns = q * unit;
  int64_t days = ns / kNsPerDay;
  int64_t tod = ns % kNsPerDay;
  if (tod < 0) tod += kNsPerDay, --days;
  // Civil date from days (H. Hinnant's civil_from_days).
  const int64_t z = days + 719468;
  const int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const int64_t doe = z - era * 146097;
  const int64_t yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const int64_t doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const int64_t mp = (5 * doy + 2) / 153;
  const int64_t d = doy - (153 * mp + 2) / 5 + 1;
  const int64_t m = mp < 10 ? mp + 3 : mp - 9;
  const int64_t y = yoe + era * 400 + (m <= 2);

  const int64_t secs = tod / kNsPerSecond;
  char time[32];
  std::snprintf(time, sizeof(time), "%02lld%02lld%02lld", static_cast<long long>(secs / 3600),
                static_cast<long long>(secs / 60 % 60), static_cast<long long>(secs % 60));
  std::string t = time;
  if (time_decimals > 0) {
    char frac[16];
    std::snprintf(frac, sizeof(frac), ".%0*lld", time_decimals,
                  static_cast<long long>((tod % kNsPerSecond) / unit));
    t += frac;
  }
  char buf[160];
  std::string out;
  std::snprintf(buf, sizeof(buf), "GNZDA,%s,%02lld,%02lld,%04lld,00,00", t.c_str(),
                static_cast<long long>(d), static_cast<long long>(m), static_cast<long long>(y));
  out += NmeaSentence(buf);
  std::snprintf(buf, sizeof(buf), "GNGGA,%s,%s,%c,%s,%c,%d,%02d,,%.6f,M,0.0,M,,", t.c_str(),
                FormatAngle(fix.latitude_deg, 2).c_str(), fix.latitude_deg < 0 ? 'S' : 'N',
                FormatAngle(fix.longitude_deg, 3).c_str(), fix.longitude_deg < 0 ? 'W' : 'E',
                TypeToQuality(fix.type), std::max(0, std::min(999, fix.num_satellites)),
                fix.height_m);
  out += NmeaSentence(buf);
  std::snprintf(buf, sizeof(buf), "GNGST,%s,,,,,%.6f,%.6f,%.6f", t.c_str(), fix.sigma_horizontal_m,
                fix.sigma_horizontal_m, fix.sigma_vertical_m);
  out += NmeaSentence(buf);
  return out;
}

}  // namespace slam_mms::io_internal
