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
#include <optional>
#include <string>

#include "slam_mms/core/status.hpp"
#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/io/extrinsics_yaml.hpp"

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
  /// A calibration file, read by ReadExtrinsicsFile: extrinsics.yaml (.yaml/.yml: T_body_lidar,
  /// t_body_antenna_m, lidar_time_offset_s) or a KITTI calib_imu_to_velo.txt (any other name;
  /// kitti_calibration.hpp); empty = none. It applies to every kind through OverrideExtrinsics:
  /// it replaces a KITTI raw drive's calib_imu_to_velo.txt, a folder's DIR/extrinsics.yaml and a
  /// bag's identity default (logged where not given); its antenna lever arm replaces the drive's
  /// only where it gives one, and a nonzero lidar_time_offset_s moves the scan stamps onto the
  /// IMU clock.
  std::filesystem::path extrinsics;
  /// An IMU noise file (io/imu_noise_yaml.hpp); empty = none. Replaces the input's own
  /// (DriveStreams::imu_noise) for every kind through OverrideImuNoise: how a bag, which holds
  /// none, or a KITTI drive gets its IMU's datasheet.
  std::filesystem::path imu_noise;
  /// KITTI's HDL-64E recordings have every point about 0.2 deg too low (a defect of the
  /// dataset's intrinsic calibration; KISS-ICP and CT-ICP correct it by 0.205 deg). Nonzero: each
  /// point of a KITTI raw drive, or of a folder's KITTI .bin scans, is rotated up by this angle
  /// [deg] about p x z (KittiRawReader::Options::vertical_angle_correction); 0 (default): the
  /// points as recorded. For KITTI's own drives only: other sensors and the simulator (without
  /// --elevation-bias) have no such defect. InvalidArgument beyond +-5 deg.
  double kitti_vertical_correction_deg = 0.0;
  /// KITTI raw drives: how long before its OXTS record an IMU sample is stamped [s]
  /// (KittiRawReader::Options::oxts_inertial_delay_s); unset = estimated from the records
  /// (KITTI's own: 50-55 ms; the simulator's: 0). 0 = as recorded.
  std::optional<double> kitti_oxts_inertial_delay_s;
};

/// The kind kAuto would pick for `path` (kKittiRaw where nothing else fits).
DriveSourceKind DetectDriveSourceKind(const std::filesystem::path& path);

/// `base` with its calibration replaced by `extrinsics`: streams().T_body_lidar is
/// extrinsics.T_body_lidar; streams().t_body_antenna_m is extrinsics.t_body_antenna_m where given,
/// else the base's. Where extrinsics.lidar_time_offset_s != 0 the scans are moved onto the IMU
/// clock: ScanStart(i), ScanEnd(i) and ReadScan(i)'s stamp_start, stamp_end and stamp_trigger are
/// the base's + lidar_time_offset_s (rounded to the nanosecond); per-point time offsets are
/// relative to stamp_start and stay. Everything else is forwarded to `base`, which the returned
/// reader owns. Thread safety: as `base`.
std::unique_ptr<DriveReader> OverrideExtrinsics(std::unique_ptr<DriveReader> base,
                                                const DriveExtrinsics& extrinsics);
/// The same over a `base` the caller keeps (it must outlive the returned reader).
std::unique_ptr<DriveReader> OverrideExtrinsics(const DriveReader& base,
                                                const DriveExtrinsics& extrinsics);

/// `base` with streams().imu_noise = imu_noise and imu_noise_source = source; everything else
/// forwarded to `base`, which the returned reader owns.
std::unique_ptr<DriveReader> OverrideImuNoise(std::unique_ptr<DriveReader> base,
                                              const ImuNoiseSpec& imu_noise,
                                              const std::string& source);

[[nodiscard]] StatusOr<std::unique_ptr<DriveReader>> OpenDrive(const std::filesystem::path& path,
                                                               const DriveSourceOptions& options);

}  // namespace slam_mms
