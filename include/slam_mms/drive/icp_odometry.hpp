#pragma once
// IcpOdometry: the plainest LiDAR odometry, frame-to-frame point-to-plane ICP, as a difficulty
// gauge of a drive (issue 16: how hard are these scans, real or simulated, for registration
// alone?). No IMU, no GNSS, no map: each scan is registered to the previous one.
//
// Per scan k: starting from the constant-velocity prediction (the last registration's motion,
// scaled by the time between scan starts), its points are de-skewed to the scan start with the
// motion (constant velocity over the sweep), reduced to one point per `source_voxel_m` voxel and
// registered (PointIcp, point-to-plane, Huber) to the previous de-skewed scan (one point per
// `target_voxel_m`); de-skew and registration repeat with the motion found (`deskew_passes`). The
// poses chain: T_world_lidar(k) = T_world_lidar(k-1) * T_prev_curr, and T_world_body =
// T_world_lidar * T_lidar_body with the drive's T_body_lidar. The first pose is
// `T_world_body_first` (relative errors do not depend on it).
//
// Thread safety: a free function; reads the reader only.

#include <Eigen/Geometry>
#include <atomic>
#include <cstddef>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms {

struct IcpOdometryOptions {
  double source_voxel_m = 0.5;
  double target_voxel_m = 0.2;
  double max_correspondence_m = 1.0;
  double huber_delta_m = 0.1;
  int max_iterations = 30;
  bool deskew = true;  ///< Constant-velocity de-skew (the scans' per-point times).
  /// De-skew / register passes per scan, each de-skewing with the last pass's motion (stops
  /// early when the motion changes by less than 1e-4).
  int deskew_passes = 3;
  double min_range_m = 2.0;  ///< Points closer than this are dropped (the car itself).
  int num_threads = 2;       ///< In [1, 64].
  Eigen::Isometry3d T_world_body_first = Eigen::Isometry3d::Identity();

  [[nodiscard]] Status Validate() const;  ///< InvalidArgument naming "IcpOdometryOptions::<field>".
};

struct IcpOdometryResult {
  Trajectory T_world_body;    ///< One pose per scan registered (at each scan's start).
  size_t scans_unusable = 0;  ///< Registrations that failed: the prediction was kept.
  double mean_rms_residual_m = 0.0;
};

/// Runs over every scan of `reader`; a scan that cannot be read is an error naming it. `stop`
/// (optional) ends the run early with what was computed (kCancelled is not returned).
[[nodiscard]] StatusOr<IcpOdometryResult> RunIcpOdometry(
    const DriveReader& reader, const IcpOdometryOptions& options = IcpOdometryOptions(),
    const std::atomic<bool>* stop = nullptr);

}  // namespace slam_mms
