// libFuzzer target: a KITTI scan file's bytes -> points, as KittiRawReader::ReadScan reads them.
// The first byte selects the format (.bin or extract .txt) and the reader options; the rest is the
// file. Never copy real KITTI scans into the corpus (CC BY-NC-SA): fuzz/corpus/ is synthetic.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/file_util.hpp"
#include "io/parsers.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slam_mms;
  if (size == 0) return 0;
  const uint8_t mode = data[0];
  const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  std::vector<float> xyzr;
  const Status parsed = (mode & 1) == 0 ? io_internal::ParseKittiBinScan(bytes, "fuzz.bin", &xyzr)
                                        : io_internal::ParseKittiTextScan(
                                              io_internal::SplitLines(bytes), "fuzz.txt", &xyzr);
  if (!parsed.ok()) return 0;
  KittiRawReader::Options options;
  options.spin = (mode & 2) != 0 ? SpinDirection::kCounterClockwise : SpinDirection::kClockwise;
  options.vertical_angle_correction = (mode & 4) != 0;
  options.per_point_time = (mode & 8) != 0;
  PointCloud cloud;
  const size_t dropped = io_internal::KittiPointsToCloud(xyzr, options, 0.1, &cloud);
  if (dropped + cloud.size() != xyzr.size() / 4) __builtin_trap();
  for (size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.points()[i].allFinite()) __builtin_trap();
    const float t = cloud.time_offsets_s()[i];
    if (!(t >= 0.0f && t <= 0.1f + 1e-6f)) __builtin_trap();
  }
  return 0;
}
