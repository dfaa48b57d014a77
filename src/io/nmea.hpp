#pragma once
// Private: NMEA 0183 GNSS logs (a drive folder's gnss.nmea) to GnssFix and back.
//
// Reading. Every line is one sentence "$<talker><type>,<fields>*<hh>"; the checksum (XOR of the
// characters between '$' and '*') is required and verified. Bad sentences (no '$', no or wrong
// checksum, malformed fields) are skipped and counted with their line; other sentence types are
// ignored. Used:
// - GGA: time of day, position, quality (0 none, 1 sps, 2 dgps, 4 RTK fixed, 5 RTK float; 3 PPS
//   -> single, 9 SBAS -> dgps, 6/7/8 estimated/manual/simulated -> none), satellites; ellipsoidal
//   height = altitude + geoid separation (an empty separation counts as 0). A GGA without a
//   position (quality 0, empty fields) gives no fix and is counted.
// - GST: 1-sigma latitude/longitude/altitude errors, matched to the GGA of the same time of day
//   (before or after it): sigma_horizontal = sigma_lon if it equals sigma_lat, else
//   sqrt((sigma_lat^2 + sigma_lon^2) / 2); sigma_vertical = sigma_alt. A GGA without a GST gets
//   the sigmas of NmeaDefaultSigmas (counted).
// - RMC (ddmmyy, years 80-99 -> 19xx) and ZDA (dd, mm, yyyy): the UTC date. A GGA takes the date
//   of the latest date sentence (years 1970..2200, else the sentence is bad), carried over midnight
//   when the time of day wraps (a drop of more than 12 h); a GGA before any date sentence takes the
//   date of the first date sentence if that one belongs to the same epoch (time of day within 1 s:
//   receivers send GGA before RMC), else the date of NmeaOptions::utc_date_days, else it is an
//   error naming the line.
// Fix stamps must strictly increase (an error names both lines).
//
// Writing (FormatNmeaEpoch): ZDA, GGA, GST per fix. Precision: time of day with `time_decimals`
// digits (3: 0.5 ms; 9: exact), latitude/longitude minutes with 9 decimals (<= 1 um), height and
// sigmas with 6 decimals (<= 0.5 um; receivers write fewer, the reader takes any), the ellipsoidal
// height in the altitude field with geoid separation 0, no HDOP. Round trips exactly: fix type,
// satellites, and (time_decimals 9) stamps.
//
// Thread safety: pure functions; safe from any thread.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::io_internal {

struct NmeaOptions {
  /// UTC date (days since 1970-01-01) for GGA sentences before any date sentence; none = error.
  std::optional<int64_t> utc_date_days;
};

/// What a GNSS log gave.
struct NmeaGnss {
  std::vector<GnssFix> fixes;       ///< Strictly increasing stamps.
  std::vector<int> fix_lines;       ///< 1-based line of each fix's GGA.
  size_t num_sentences = 0;         ///< Sentences with a valid checksum.
  size_t num_bad = 0;               ///< Skipped: bad checksum or malformed.
  std::vector<std::string> bad;     ///< "file:line: why" of the first kMaxListedBad bad ones.
  size_t num_ignored = 0;           ///< Other sentence types.
  size_t num_without_position = 0;  ///< GGA without a position (no fix).
  size_t num_without_gst = 0;       ///< Fixes whose sigmas are NmeaDefaultSigmas.
  size_t num_empty_separation = 0;  ///< GGA whose geoid separation was empty (taken as 0).
  static constexpr size_t kMaxListedBad = 20;
};

/// Parses a whole log; `file` names it in messages.
StatusOr<NmeaGnss> ParseNmeaGnss(std::string_view bytes, const std::string& file,
                                 const NmeaOptions& options);

/// The horizontal and vertical 1-sigma [m] given to a fix of `type` without a GST sentence:
/// RTK fixed 0.02 / 0.03, RTK float 0.5 / 0.75, dgps 1.0 / 1.5, sps 3.0 / 4.5, none 10 / 15.
void NmeaDefaultSigmas(GnssFixType type, double* sigma_horizontal_m, double* sigma_vertical_m);

/// "$" + body + "*hh\r\n".
std::string NmeaSentence(std::string_view body);

/// ZDA + GGA + GST sentences of one fix (see the file comment); `time_decimals` in [0, 9].
std::string FormatNmeaEpoch(const GnssFix& fix, int time_decimals);

/// Days since 1970-01-01 of a proleptic Gregorian date; false when the date does not exist.
bool CivilToDays(int64_t year, int64_t month, int64_t day, int64_t* days);

}  // namespace slam_mms::io_internal
