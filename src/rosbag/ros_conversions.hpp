#pragma once
// Private: sensor_msgs/NavSatFix, Imu and ROS time <-> the library's records, for
// RosbagDriveReader and WriteRosbag (conventions in rosbag_drive_reader.hpp / rosbag_writer.hpp).
//
// Thread safety: pure functions.

#include <ros/time.h>
#include <sensor_msgs/NavSatFix.h>

#include <cstdint>
#include <string>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::rosbag_internal {

/// "1317000000.000001000" (seconds since the epoch, 9 decimals), for messages.
std::string StampString(int64_t ns);

inline Timestamp FromRosTime(const ros::Time& t) {
  return Timestamp::FromNanoseconds(static_cast<int64_t>(t.toNSec()));
}
/// kInvalidArgument for a time ROS 1 cannot hold (before ros::TIME_MIN = 1 ns, or after 2106).
[[nodiscard]] StatusOr<ros::Time> ToRosTime(Timestamp t, const std::string& what);

/// Sigmas [m] of a NavSatFix's position_covariance (ENU, row-major, m^2): sqrt((c0 + c4) / 2) and
/// sqrt(c8); `unknown_*` where the covariance type is UNKNOWN or a diagonal entry is negative or
/// not finite.
void NavSatFixSigmas(const sensor_msgs::NavSatFix& msg, double unknown_sigma_horizontal_m,
                     double unknown_sigma_vertical_m, double* sigma_horizontal_m,
                     double* sigma_vertical_m);

/// NavSatStatus::status written for a fix type (kRtkFloat and kRtkFixed: STATUS_GBAS_FIX).
int8_t NavSatStatusFor(GnssFixType type);

/// A fix as NavSatFix (diagonal known covariance; no satellites count).
sensor_msgs::NavSatFix ToNavSatFix(const GnssFix& fix, const std::string& frame_id);

/// Whether a TwistStamped frame_id names an ENU-aligned frame ("enu", "world", "map", "odom",
/// case-insensitive, with or without a leading '/').
bool IsEnuFrameId(const std::string& frame_id);

}  // namespace slam_mms::rosbag_internal
