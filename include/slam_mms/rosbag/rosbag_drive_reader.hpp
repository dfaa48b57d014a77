#pragma once
// RosbagDriveReader: a ROS 1 bag (format 2.0, read with Debian's librosbag-storage; no ROS master,
// no catkin) as a DriveReader. docs/rosbag.md has the full description; in short:
//
// Topics. lidar sensor_msgs/PointCloud2, IMU sensor_msgs/Imu, GNSS sensor_msgs/NavSatFix, velocity
// geometry_msgs/TwistStamped. A topic left empty in Options is taken from the bag when exactly one
// topic of its type is there; none or several is an error listing the bag's topics and types (GNSS
// and velocity may be absent). All stamps are header.stamp.
//
// Scans. x, y, z float32 or float64; intensity (also named `i` or `reflectance`) of any numeric
// type, else 0; a per-point time field named `time`, `t` or `timestamp`: float32/float64 in
// seconds, integer types in nanoseconds (Velodyne `time` float32 relative, Ouster `t` uint32 ns
// relative, Hesai `timestamp` float64 absolute), relative to header.stamp or absolute (kAuto: a
// cloud whose first finite time is above 1e6 s is absolute). With a time field, with t relative to
// the header: stamp_start = header + min(0, min t), stamp_end = header + max t (so a driver that
// stamps the scan end and writes negative times works too). Without one, header.stamp is the scan
// start (or end, Options::header_stamp), the scan lasts scan_period_s (0: the median spacing of the
// header stamps) and per-point times come from the azimuth over [start, end] exactly as for KITTI
// (KittiAzimuthFraction). stamp_trigger = header.stamp; Scan::index = the message number on the
// lidar topic (0-based, in bag order). is_bigendian, a missing x/y/z, a field outside point_step or
// of an unknown type fail Open; a cloud whose data size disagrees with row_step x height, whose
// times lie more than 10 s from its stamp, or that is empty, is kDataLoss at ReadScan (naming bag,
// topic, message number and field; logged by Open) so the caller may skip it.
//
// IMU: body frame, linear_acceleration = specific force [m/s^2], angular_velocity [rad/s]. The
// initial attitude R_enu_body (ENU, as kitti2bag and robot_localization write it) is the
// orientation of the last message at or before the first scan's start (else the first after it)
// among those with orientation_covariance[0] >= 0 and a unit quaternion.
// Velocity: the TwistStamped nearest in time to that attitude; header.frame_id "enu", "world",
// "map" or "odom" is ENU, anything else is the body frame (kitti2bag's /kitti/oxts/gps/vel) and is
// rotated by the attitude. Without an attitude there is no initial state.
//
// GNSS. NavSatFix cannot say RTK float vs fixed; the convention (RosbagFixType):
// STATUS_NO_FIX (-1) -> kNone, STATUS_FIX (0) -> kSingle, STATUS_SBAS_FIX (1) -> kDifferential,
// STATUS_GBAS_FIX (2) -> kRtkFixed where sigma_horizontal <= rtk_fixed_max_sigma_horizontal_m
// (0.05 m), else kRtkFloat. Sigmas from position_covariance (ENU, m^2): sigma_horizontal =
// sqrt((c[0] + c[4]) / 2), sigma_vertical = sqrt(c[8]); COVARIANCE_TYPE_UNKNOWN (or a negative or
// non-finite diagonal) gives the Options' unknown_covariance_* sigmas. A fix with a NaN latitude,
// longitude or altitude is skipped and counted (NumSkippedGnssFixes). num_satellites = 0.
//
// Every stream (including the lidar topic) must be strictly increasing in header.stamp, in the
// bag's receipt-time order; else Open fails naming bag, topic, message number and both stamps.
// Sources are "<bag>: <topic> message <n>" (n 0-based).
//
// Ownership: owns the open bag, the index of the scans (about 100 bytes each, no points) and the
// IMU/GNSS streams, read into memory by Open in one pass over the four topics (the bag file is
// read once); Open deserialises each cloud of the range once (one at a time, constant memory) for
// its stamps. ReadScan reads one message from the bag. Not copyable; movable only as the
// unique_ptr Open returns. No exception leaves this class: rosbag, boost and ROS serialization
// exceptions become a Status naming the bag.
// Thread safety: const methods may be called concurrently; ReadScan serialises its bag access
// through a mutex (rosbag::Bag is not thread-safe) and decodes outside it.

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"

namespace slam_mms {

/// One topic of a bag, for listings and error messages.
struct RosbagTopic {
  std::string name;      ///< "/velodyne_points"
  std::string datatype;  ///< "sensor_msgs/PointCloud2"
  uint64_t num_messages = 0;
};

/// The NavSatFix status -> GnssFixType convention above (status is NavSatStatus::status).
GnssFixType RosbagFixType(int status, double sigma_horizontal_m,
                          double rtk_fixed_max_sigma_horizontal_m = 0.05);

class RosbagDriveReader final : public DriveReader {
 public:
  /// How a per-point time field is read.
  enum class TimeField {
    kAuto,              ///< Absolute where the cloud's first finite time is > 1e6 s, else relative.
    kRelativeToHeader,  ///< Seconds (integer fields: ns) from header.stamp.
    kAbsolute,          ///< Seconds (integer fields: ns) since the Unix epoch.
  };
  /// What header.stamp of a cloud without a time field means.
  enum class HeaderStamp { kScanStart, kScanEnd };

  struct Options {
    /// Topics; "" = the only topic of that type in the bag (GNSS, velocity: none is allowed).
    std::string lidar_topic;
    std::string imu_topic;
    std::string gnss_topic;
    std::string velocity_topic;
    /// Calibration, not in a bag (slam_mms_run reads it from --extrinsics FILE.yaml).
    Eigen::Isometry3d T_body_lidar = Eigen::Isometry3d::Identity();
    std::optional<Eigen::Vector3d> t_body_antenna_m;
    /// Whether the IMU frame is the vehicle's (DriveStreams::imu_frame_is_vehicle_frame; a bag
    /// does not say: an --extrinsics file's imu_frame_is_vehicle_frame).
    bool imu_frame_is_vehicle_frame = false;
    /// Scan range: message numbers on the lidar topic (0-based), inclusive; -1 = the last one.
    int64_t first_scan = 0;
    int64_t last_scan = -1;
    /// With a scan range (first_scan > 0 or last_scan >= 0), the IMU and GNSS records kept are
    /// those within [first scan start - margin, last scan end + margin] [s] (as KittiRawReader);
    /// without one, the whole bag's.
    double stream_time_margin_s = 1.0;
    /// Clouds without a time field: spin for the azimuth time, and whether to compute it (false:
    /// all offsets 0).
    SpinDirection spin = SpinDirection::kClockwise;
    bool per_point_time = true;
    /// Clouds without a time field: scan duration [s]; 0 = the median spacing of the header
    /// stamps of the selected scans (0.1 s with fewer than two scans).
    double scan_period_s = 0.0;
    TimeField time_field = TimeField::kAuto;
    HeaderStamp header_stamp = HeaderStamp::kScanStart;
    /// NavSatFix with COVARIANCE_TYPE_UNKNOWN: the sigmas used [m].
    double unknown_covariance_sigma_horizontal_m = 1.0;
    double unknown_covariance_sigma_vertical_m = 1.5;
    /// STATUS_GBAS_FIX is kRtkFixed up to this horizontal sigma [m], kRtkFloat above.
    double rtk_fixed_max_sigma_horizontal_m = 0.05;

    Options() {}  // NOLINT(modernize-use-equals-default): GCC 12 and nested defaults
    [[nodiscard]] Status Validate() const;
  };

  /// Opens `bag`, chooses the topics, reads the IMU/GNSS/velocity topics and indexes the scans.
  /// kNotFound for a missing file, kInvalidArgument for a topic that is missing, ambiguous or of
  /// the wrong type (listing the bag's topics), kDataLoss for a corrupt or truncated bag or a
  /// stream going backwards.
  [[nodiscard]] static StatusOr<std::unique_ptr<RosbagDriveReader>> Open(
      const std::filesystem::path& bag, const Options& options);

  /// The topics of `bag` with their types and message counts.
  [[nodiscard]] static StatusOr<std::vector<RosbagTopic>> ListTopics(
      const std::filesystem::path& bag);

  ~RosbagDriveReader() override;
  RosbagDriveReader(const RosbagDriveReader&) = delete;
  RosbagDriveReader& operator=(const RosbagDriveReader&) = delete;

  std::string Describe() const override;
  size_t NumScans() const override;
  Timestamp ScanStart(size_t i) const override;
  Timestamp ScanEnd(size_t i) const override;
  std::string ScanSource(size_t i) const override;
  [[nodiscard]] StatusOr<Scan> ReadScan(size_t i) const override;
  const DriveStreams& streams() const override;
  uint64_t TotalDroppedPoints() const override;

  const Options& options() const;
  const std::filesystem::path& bag_path() const;
  /// The topics in use ("" where none: GNSS, velocity).
  const std::string& lidar_topic() const;
  const std::string& imu_topic() const;
  const std::string& gnss_topic() const;
  const std::string& velocity_topic() const;
  /// Whether scan i's cloud has a per-point time field (known from the index).
  bool ScanHasTimeField(size_t i) const;
  /// NavSatFix messages skipped for a NaN latitude/longitude/altitude.
  uint64_t NumSkippedGnssFixes() const;

 private:
  struct Impl;
  explicit RosbagDriveReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
