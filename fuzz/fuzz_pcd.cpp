// libFuzzer target: a drive folder's scan file bytes (PCD, or PLY when they start with "ply") ->
// ParseScanFile, as FolderDriveReader::ReadScan reads them (shared with the map readers through
// point_file_format.hpp); the same bytes as a KITTI .bin. A parsed scan has 4 values per point
// and at most the declared number of points; one written by FormatScanFile parses back to itself.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

#include "io/drive_folder_parsers.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slam_mms;
  using io_internal::ScanFileKind;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const ScanFileKind kind = bytes.substr(0, 3) == "ply" ? ScanFileKind::kPly : ScanFileKind::kPcd;
  io_internal::ScanFilePoints points;
  if (io_internal::ParseScanFile(bytes, kind, "fuzz", &points).ok()) {
    const size_t n = points.xyzr.size() / 4;
    if (points.xyzr.size() % 4 != 0 || n != points.declared_points) __builtin_trap();
    if (!points.time_field.empty() && points.time_s.size() != n) __builtin_trap();
    // Finite points written back as binary PCD/PLY parse to the same floats.
    PointCloud cloud;
    for (size_t i = 0; i < n && i < 64; ++i) {
      const float* v = &points.xyzr[4 * i];
      cloud.Add(Eigen::Vector3f(v[0], v[1], v[2]), v[3],
                points.time_s.empty() ? 0.0f : points.time_s[i]);
    }
    for (const ScanFileKind k : {ScanFileKind::kPcd, ScanFileKind::kPly}) {
      const std::string again = io_internal::FormatScanFile(cloud, k, false, true);
      io_internal::ScanFilePoints back;
      if (!io_internal::ParseScanFile(again, k, "again", &back).ok()) __builtin_trap();
      if (back.xyzr.size() != 4 * cloud.size() ||
          (!back.xyzr.empty() &&
           std::memcmp(back.xyzr.data(), points.xyzr.data(), back.xyzr.size() * 4) != 0)) {
        __builtin_trap();
      }
    }
  }
  io_internal::ScanFilePoints bin;
  (void)io_internal::ParseScanFile(bytes, ScanFileKind::kKittiBin, "fuzz.bin", &bin);
  return 0;
}
