#pragma once
// OpenDrive: any drive input as a DriveReader, for hosts that take a path from their user
// (slam_mms_run, slam_mms_bench_e2e, slam_mms_convert, the Python package).
//
// Kinds: a KITTI raw drive folder (KittiDriveReader), a plain drive folder (FolderDriveReader,
// docs/drive_folder.md) or a ROS 1 bag (RosbagDriveReader, docs/rosbag.md; only where the library
// was built with SLAM_MMS_WITH_ROSBAG, else kUnimplemented). kAuto detects: a regular file ending
// in .bag is a bag; a folder with scans.csv is a plain drive folder; else KITTI raw.
//
// Thread safety: a pure function; the readers it returns document their own.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "slam_mms/core/status.hpp"
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms {

enum class DriveSourceKind { kAuto, kKittiRaw, kFolder, kRosbag };

/// "auto", "kitti_raw", "folder", "rosbag".
const char* DriveSourceKindName(DriveSourceKind kind);

struct DriveSourceOptions {
  DriveSourceKind kind = DriveSourceKind::kAuto;
  /// First and last scan (inclusive): KITTI file numbers; scan numbers in file order for folders
  /// and bags. last_frame = -1: to the end.
  int64_t first_frame = 0;
  int64_t last_frame = -1;
  /// Bag topics; empty = the one topic of each message type in the bag.
  std::string lidar_topic;
  std::string imu_topic;
  std::string gnss_topic;
  /// extrinsics.yaml (T_body_lidar, t_body_antenna_m); empty = none. Bags take it (else identity,
  /// logged); for a folder it overrides DIR/extrinsics.yaml; KITTI raw: kInvalidArgument (its
  /// calibration is calib_imu_to_velo.txt).
  std::filesystem::path extrinsics;
};

/// The kind kAuto would pick for `path` (kKittiRaw where nothing else fits).
DriveSourceKind DetectDriveSourceKind(const std::filesystem::path& path);

[[nodiscard]] StatusOr<std::unique_ptr<DriveReader>> OpenDrive(const std::filesystem::path& path,
                                                               const DriveSourceOptions& options);

}  // namespace slam_mms
