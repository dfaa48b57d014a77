#pragma once
// The drive-result folder: a finished drive (DriveResult) on disk, written by slam_mms_run
// (--drive-result) and read by the multi-drive adjustment (slam_mms_merge).
//
//   DIR/drive_result.json       format "slam_mms_drive_result", version, origin, T_body_lidar,
//                               GNSS availability, submaps (id, times, T_world_submap, scans with
//                               T_submap_scan and covariance, cloud file names), level-2 factors
//   DIR/submaps/NNNNNN_map.pcd  each submap's map cloud (submap frame, binary PCD, intensity)
//   DIR/submaps/NNNNNN_reg.pcd  its registration cloud
//
// Poses are [tx, ty, tz, qx, qy, qz, qw] (metres; unit quaternion), covariances 36 numbers row
// major (rotation first), times integer nanoseconds since the Unix epoch (UTC). Numbers are written
// with round-trip precision (a rotation within its last digit: quaternion <-> matrix). Readers
// refuse another format or a newer version, naming the file and the field.
//
// Thread safety: pure functions.

#include <filesystem>

#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/drive_result.hpp"

namespace slam_mms {

inline constexpr int kDriveResultVersion = 1;
inline constexpr char kDriveResultFileName[] = "drive_result.json";

/// Writes `result` into `dir` (created if missing; existing files replaced).
[[nodiscard]] Status WriteDriveResult(const DriveResult& result, const std::filesystem::path& dir);
/// Reads a folder written by WriteDriveResult. NotFound / InvalidArgument / DataLoss naming the
/// file and the field.
[[nodiscard]] StatusOr<DriveResult> ReadDriveResult(const std::filesystem::path& dir);

}  // namespace slam_mms
