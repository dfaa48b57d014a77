#include "rosbag/ros_conversions.hpp"

#include <sensor_msgs/NavSatStatus.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "slam_mms/rosbag/rosbag_drive_reader.hpp"

namespace slam_mms {

GnssFixType RosbagFixType(int status, double sigma_horizontal_m,
                          double rtk_fixed_max_sigma_horizontal_m) {
  using sensor_msgs::NavSatStatus;
  switch (status) {
    case NavSatStatus::STATUS_FIX: return GnssFixType::kSingle;
    case NavSatStatus::STATUS_SBAS_FIX: return GnssFixType::kDifferential;
    case NavSatStatus::STATUS_GBAS_FIX:
      return sigma_horizontal_m <= rtk_fixed_max_sigma_horizontal_m ? GnssFixType::kRtkFixed
                                                                    : GnssFixType::kRtkFloat;
    default: return GnssFixType::kNone;  // STATUS_NO_FIX and anything unknown
  }
}

namespace rosbag_internal {

std::string StampString(int64_t ns) {
  char buf[40];
  const int64_t sec = ns >= 0 ? ns / 1000000000 : -((-ns + 999999999) / 1000000000);
  std::snprintf(buf, sizeof(buf), "%lld.%09lld", static_cast<long long>(sec),
                static_cast<long long>(ns - sec * 1000000000));
  return buf;
}

StatusOr<ros::Time> ToRosTime(Timestamp t, const std::string& what) {
  const int64_t ns = t.nanoseconds();
  constexpr int64_t kMaxNs = static_cast<int64_t>(UINT32_MAX) * 1000000000 + 999999999;
  if (ns < 1 || ns > kMaxNs) {
    return InvalidArgumentError(what + ": stamp " + StampString(ns) +
                                " s cannot be written to a ROS 1 bag (1 ns .. 2106)");
  }
  ros::Time r;
  r.fromNSec(static_cast<uint64_t>(ns));
  return r;
}

void NavSatFixSigmas(const sensor_msgs::NavSatFix& msg, double unknown_sigma_horizontal_m,
                     double unknown_sigma_vertical_m, double* sigma_horizontal_m,
                     double* sigma_vertical_m) {
  const auto& c = msg.position_covariance;
  const bool usable = [&] {
    if (msg.position_covariance_type == sensor_msgs::NavSatFix::COVARIANCE_TYPE_UNKNOWN) {
      return false;
    }
    for (double v : {c[0], c[4], c[8]}) {
      if (!std::isfinite(v) || v < 0.0) return false;
    }
    return true;
  }();
  if (!usable) {
    *sigma_horizontal_m = unknown_sigma_horizontal_m;
    *sigma_vertical_m = unknown_sigma_vertical_m;
    return;
  }
  // Exactly sqrt(c0) where c0 == c4 (the writer's case): (c + c) / 2 == c in binary floating point.
  *sigma_horizontal_m = std::sqrt(0.5 * (c[0] + c[4]));
  *sigma_vertical_m = std::sqrt(c[8]);
}

int8_t NavSatStatusFor(GnssFixType type) {
  using sensor_msgs::NavSatStatus;
  switch (type) {
    case GnssFixType::kNone: return NavSatStatus::STATUS_NO_FIX;
    case GnssFixType::kSingle: return NavSatStatus::STATUS_FIX;
    case GnssFixType::kDifferential: return NavSatStatus::STATUS_SBAS_FIX;
    case GnssFixType::kRtkFloat:
    case GnssFixType::kRtkFixed: return NavSatStatus::STATUS_GBAS_FIX;
  }
  return NavSatStatus::STATUS_NO_FIX;
}

sensor_msgs::NavSatFix ToNavSatFix(const GnssFix& fix, const std::string& frame_id) {
  sensor_msgs::NavSatFix msg;
  msg.header.frame_id = frame_id;
  msg.status.status = NavSatStatusFor(fix.type);
  msg.status.service = sensor_msgs::NavSatStatus::SERVICE_GPS;
  msg.latitude = fix.latitude_deg;
  msg.longitude = fix.longitude_deg;
  msg.altitude = fix.height_m;
  msg.position_covariance.fill(0.0);
  msg.position_covariance[0] = fix.sigma_horizontal_m * fix.sigma_horizontal_m;
  msg.position_covariance[4] = fix.sigma_horizontal_m * fix.sigma_horizontal_m;
  msg.position_covariance[8] = fix.sigma_vertical_m * fix.sigma_vertical_m;
  msg.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN;
  return msg;
}

bool IsEnuFrameId(const std::string& frame_id) {
  std::string f = frame_id;
  if (!f.empty() && f.front() == '/') f.erase(0, 1);
  std::transform(f.begin(), f.end(), f.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return f == "enu" || f == "world" || f == "map" || f == "odom";
}

}  // namespace rosbag_internal
}  // namespace slam_mms
