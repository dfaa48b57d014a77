#pragma once
// The plain sensor records the library consumes: Scan, ImuSample, GnssFix, InsState.
// (Small value structs kept together; each is documented where it is declared.)
//
// Thread safety: value types.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

/// One LiDAR revolution, points in the `lidar` frame, not motion-compensated.
struct Scan {
  int64_t index = -1;       ///< Frame index in its drive (file number), -1 if unknown.
  Timestamp stamp_start;    ///< Time of the first firing (the scan's reference time).
  Timestamp stamp_end;      ///< Time of the last firing.
  Timestamp stamp_trigger;  ///< KITTI `timestamps.txt` (camera trigger, about mid-scan).
  PointCloud cloud;         ///< Points with per-point time offsets from stamp_start.
  std::string source;       ///< File it came from, for messages ("" if none).

  double DurationSeconds() const { return stamp_end.SecondsSince(stamp_start); }
};

/// One IMU measurement in the `body` frame.
struct ImuSample {
  Timestamp stamp;
  Eigen::Vector3d accel_mps2 =
      Eigen::Vector3d::Zero();  ///< Specific force (gravity included) [m/s^2].
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();  ///< Angular rate [rad/s].
};

/// GNSS solution quality, ordered from worst to best.
enum class GnssFixType { kNone = 0, kSingle = 1, kDifferential = 2, kRtkFloat = 3, kRtkFixed = 4 };

const char* GnssFixTypeName(GnssFixType type);

/// One GNSS position fix (of the antenna) in WGS-84.
struct GnssFix {
  Timestamp stamp;
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;            ///< Height as the receiver reports it (KITTI OXTS "alt").
  double sigma_horizontal_m = 1.0;  ///< Reported 1-sigma horizontal accuracy [m].
  double sigma_vertical_m = 1.5;    ///< Reported 1-sigma vertical accuracy [m].
  GnssFixType type = GnssFixType::kSingle;
  int num_satellites = 0;
};

/// A navigation state of the body: what the POS (InsFilter) and the Localizer produce.
struct InsState {
  Timestamp stamp;
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  Eigen::Vector3d v_world_mps = Eigen::Vector3d::Zero();  ///< Velocity of the body in `world`.
  /// Covariance of T_world_body, rotation first [omega, v], right perturbation T = T_hat * Exp(d).
  Matrix6d cov_T_world_body = Matrix6d::Identity();
  Eigen::Vector3d accel_bias_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias_radps = Eigen::Vector3d::Zero();
};

}  // namespace slam_mms
