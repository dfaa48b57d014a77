// libFuzzer target: a gnss.nmea log -> ParseNmeaGnss as FolderDriveReader reads it; fixes must be
// strictly increasing with finite values, and a fix written by FormatNmeaEpoch (9 decimals) parses
// back to the same stamp, fix type and satellites.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/nmea.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slam_mms;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  io_internal::NmeaOptions options;
  if (size > 0 && data[0] == '$') options.utc_date_days = 15000;
  auto nmea = io_internal::ParseNmeaGnss(bytes, "fuzz.nmea", options);
  if (!nmea.ok()) return 0;
  if (nmea->fixes.size() != nmea->fix_lines.size()) __builtin_trap();
  for (size_t i = 0; i < nmea->fixes.size(); ++i) {
    const GnssFix& f = nmea->fixes[i];
    if (!std::isfinite(f.latitude_deg) || !std::isfinite(f.longitude_deg) ||
        !std::isfinite(f.height_m) || std::abs(f.latitude_deg) > 90.0 ||
        std::abs(f.longitude_deg) > 180.0 || !(f.sigma_horizontal_m >= 0.0)) {
      __builtin_trap();
    }
    if (i > 0 && f.stamp <= nmea->fixes[i - 1].stamp) __builtin_trap();
  }
  if (!nmea->fixes.empty()) {
    const GnssFix& f = nmea->fixes.front();
    if (std::abs(f.height_m) < 1e6 && f.sigma_horizontal_m < 1e6 && f.sigma_vertical_m < 1e6) {
      auto back = io_internal::ParseNmeaGnss(io_internal::FormatNmeaEpoch(f, 9), "again", {});
      if (!back.ok() || back->fixes.size() != 1 || back->fixes[0].stamp != f.stamp ||
          back->fixes[0].type != f.type || back->fixes[0].num_satellites != f.num_satellites) {
        __builtin_trap();
      }
    }
  }
  return 0;
}
