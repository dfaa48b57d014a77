// libFuzzer target: an oxts/data/NNNNNNNNNN.txt file's bytes -> OxtsRecord -> GnssFix, ImuSample,
// attitude, as KittiRawReader reads OXTS records; a parsed record must survive Format/Parse.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/file_util.hpp"
#include "io/parsers.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slam_mms;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto record = io_internal::ParseOxtsFileLines(io_internal::SplitLines(bytes), "fuzz.txt");
  if (!record.ok()) return 0;
  const Timestamp stamp = Timestamp::FromNanoseconds(1317042651106324297LL);
  const GnssFix fix = ToGnssFix(*record, stamp);
  const ImuSample imu = ToImuSample(*record, stamp);
  const Eigen::Matrix3d R = OxtsAttitude(*record);
  if (!R.allFinite() || !imu.accel_mps2.allFinite() || !std::isfinite(fix.latitude_deg)) {
    __builtin_trap();
  }
  auto again = ParseOxtsLine(FormatOxtsLine(*record), "fuzz.txt", 1);
  if (!again.ok() || again->ToArray() != record->ToArray()) __builtin_trap();
  return 0;
}
