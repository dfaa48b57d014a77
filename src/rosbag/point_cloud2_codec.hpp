#pragma once
// Private: sensor_msgs/PointCloud2 <-> PointCloud for RosbagDriveReader and WriteRosbag (the
// conventions are in rosbag_drive_reader.hpp). Kept apart from the bag access so the tests can
// build malformed clouds in memory. `source` only names the message in errors ("<bag>: <topic>
// message <n>").
//
// Thread safety: pure functions.

#include <sensor_msgs/PointCloud2.h>

#include <cstdint>
#include <string>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/rosbag/rosbag_drive_reader.hpp"

namespace slam_mms::rosbag_internal {

/// One PointField in use: byte offset in the point and sensor_msgs::PointField datatype.
struct FieldRef {
  std::string name;  ///< "" = absent.
  uint32_t offset = 0;
  uint8_t datatype = 0;
  bool present() const { return !name.empty(); }
};

/// Where x, y, z, intensity and the per-point time are in each point.
struct CloudLayout {
  FieldRef x, y, z;
  FieldRef intensity;  ///< `intensity`, `i` or `reflectance`; optional.
  FieldRef time;       ///< `time`, `t` or `timestamp`; optional.
};

/// Validates the fields: little endian, x/y/z float32 or float64, known datatypes, every field
/// used inside point_step. kDataLoss naming `source` and the field otherwise.
[[nodiscard]] StatusOr<CloudLayout> ParseCloudLayout(const sensor_msgs::PointCloud2& msg,
                                                     const std::string& source);

/// data.size() == row_step * height, row_step >= width * point_step: kDataLoss naming the field.
[[nodiscard]] Status CheckCloudSize(const sensor_msgs::PointCloud2& msg, const std::string& source);

/// Per-point times of a cloud with a time field, relative to header.stamp [s], over its finite
/// values (a cloud without a finite time gives 0, 0). kDataLoss where they lie more than 10 s from
/// the stamp (a wrong convention or unit).
struct CloudTimeRange {
  double min_s = 0.0;
  double max_s = 0.0;
  bool absolute = false;  ///< What kAuto decided (or the convention given).
};
[[nodiscard]] StatusOr<CloudTimeRange> ComputeCloudTimeRange(
    const sensor_msgs::PointCloud2& msg, const CloudLayout& layout,
    RosbagDriveReader::TimeField convention, const std::string& source);

struct DecodeParams {
  RosbagDriveReader::TimeField time_field = RosbagDriveReader::TimeField::kAuto;
  /// With a time field: stamp_start - header.stamp [s] (<= 0); offsets are t_rel - this.
  double start_from_header_s = 0.0;
  /// Without a time field: the scan duration for the azimuth time [s].
  double duration_s = 0.1;
  SpinDirection spin = SpinDirection::kClockwise;
  bool per_point_time = true;
};

/// Decodes a cloud that passed ParseCloudLayout and CheckCloudSize into `cloud` (lidar frame,
/// offsets from the scan start), dropping points with a non-finite coordinate, intensity or time.
/// Returns the number dropped.
size_t DecodeCloud(const sensor_msgs::PointCloud2& msg, const CloudLayout& layout,
                   const DecodeParams& params, PointCloud* cloud);

/// The writer's cloud: height 1, x y z intensity float32 (+ `time` float32 [s] from the stamp).
void EncodeCloud(const PointCloud& cloud, bool with_time, sensor_msgs::PointCloud2* msg);

}  // namespace slam_mms::rosbag_internal
