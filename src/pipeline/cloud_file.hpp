#pragma once
// Spill files of submap point clouds: a small binary format private to the pipeline, written when
// a finished submap's cloud leaves memory (Localizer::Options::spill_dir) and read back on demand.
//
//   "SMMSCLD1" (8 bytes) | uint64 point count n | n x (float x, y, z, intensity), little endian
//
// Per-point time offsets are not stored (the accumulated map clouds have none).

#include <filesystem>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::internal {

/// Writes `cloud` to `path` (replacing it). Unavailable naming the file when it cannot be written
/// completely (e.g. the disk is full); a partial file is removed.
Status WriteCloudFile(const std::filesystem::path& path, const PointCloud& cloud);

/// Reads a file written by WriteCloudFile. NotFound when it cannot be opened; DataLoss naming the
/// file and what is wrong (magic, count, size) when it is truncated or corrupt.
StatusOr<PointCloud> ReadCloudFile(const std::filesystem::path& path);

}  // namespace slam_mms::internal
