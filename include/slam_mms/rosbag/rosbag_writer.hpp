#pragma once
// WriteRosbag: writes any DriveReader's drive as a ROS 1 bag (format 2.0) that RosbagDriveReader,
// rosbag and kitti2bag-era tools read: for tests, and for `slam_mms_convert`.
//
// Messages (receipt time = header.stamp for all):
// - lidar: sensor_msgs/PointCloud2, height 1, fields x y z intensity float32 (+ `time` float32
//   seconds from header.stamp = the scan start, unless write_point_time is false), little endian,
//   is_dense; header.seq = Scan::index;
// - IMU: sensor_msgs/Imu, linear_acceleration/angular_velocity as ImuSample; the covariances are
//   unknown (all 0) for both. The initial state's attitude (R_world_body, ENU) is written as the
//   orientation of one message only: the one at the initial state's stamp, else the first; every
//   other message has orientation identity with orientation_covariance[0] = -1 (ROS: "no
//   estimate"). A POS of every message would need an attitude the DriveReader does not have.
// - GNSS: sensor_msgs/NavSatFix, status from the fix type (kNone -> STATUS_NO_FIX, kSingle -> FIX,
//   kDifferential -> SBAS, kRtkFloat/kRtkFixed -> GBAS: RosbagFixType reads them back),
//   position_covariance diag(sh^2, sh^2, sv^2) COVARIANCE_TYPE_DIAGONAL_KNOWN; num_satellites is
//   lost (NavSatFix has no field for it).
// - velocity: one geometry_msgs/TwistStamped at the initial state's stamp, v_world_mps in ENU,
//   frame_id "enu".
// Calibration (T_body_lidar, lever arm) and external POS records are not written: ROS bags keep
// them in /tf_static or not at all; pass them to RosbagDriveReader::Options.
//
// Scans are read and written one at a time (constant memory). A scan the reader cannot read fails
// the write (the status names it) unless skip_unreadable_scans.
//
// Thread safety: reentrant; it calls the reader's const methods from the calling thread only.

#include <filesystem>
#include <string>

#include "slam_mms/core/status.hpp"
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms {

struct RosbagWriteOptions {
  std::string lidar_topic = "/velodyne_points";
  std::string imu_topic = "/imu/data";
  std::string gnss_topic = "/gps/fix";
  std::string velocity_topic = "/gps/vel";
  std::string lidar_frame_id = "velodyne";
  std::string imu_frame_id = "imu_link";
  std::string gnss_frame_id = "gps";
  /// Write the per-point `time` field (false: x y z intensity only, as kitti2bag).
  bool write_point_time = true;
  /// Skip (and log) scans whose ReadScan returns kDataLoss instead of failing.
  bool skip_unreadable_scans = false;
  enum class Compression { kNone, kLz4, kBz2 };
  Compression compression = Compression::kNone;

  [[nodiscard]] Status Validate() const;
};

/// Writes `reader`'s scans, IMU, GNSS and initial velocity to `bag` (overwritten), as above.
/// kInvalidArgument for bad options, kUnavailable where the bag cannot be written, the reader's
/// status for a scan it cannot read.
[[nodiscard]] Status WriteRosbag(const DriveReader& reader, const std::filesystem::path& bag,
                                 const RosbagWriteOptions& options);

}  // namespace slam_mms
