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
/// What ReadDriveResult loads.
struct DriveResultReadOptions {
  /// Load every submap's map cloud. false: DriveSubmap::map_cloud stays empty (the files are
  /// checked to exist); ReadDriveResultCloud loads one when it is needed. The map clouds are most
  /// of a drive result (220 of 238 MB for a 3-minute drive): an adjustment over many drives reads
  /// them one at a time (DownsampledUnionMap) rather than all at once.
  bool map_clouds = true;
};

/// Reads a folder written by WriteDriveResult. NotFound / InvalidArgument / DataLoss naming the
/// file and the field.
[[nodiscard]] StatusOr<DriveResult> ReadDriveResult(
    const std::filesystem::path& dir,
    const DriveResultReadOptions& options = DriveResultReadOptions());

enum class DriveResultCloud { kMap, kRegistration };
/// One submap's cloud of a drive-result folder (as ReadDriveResult loads it into DriveSubmap).
/// NotFound / DataLoss naming the file.
[[nodiscard]] StatusOr<PointCloud> ReadDriveResultCloud(const std::filesystem::path& dir,
                                                        SubmapId id, DriveResultCloud kind);

}  // namespace slam_mms
