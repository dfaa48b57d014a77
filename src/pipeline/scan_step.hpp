#pragma once
// ScanStep: one scan's working values, handed from stage to stage of Localizer::ProcessScan (each
// stage reads what the stages before it wrote), and the stages' stopwatch. Private to the
// pipeline module.
//
// Thread safety: a plain value.

#include <Eigen/Geometry>
#include <chrono>
#include <optional>

#include "backend/sliding_window_graph.hpp"
#include "pipeline/motion_prior.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/surfel/vertex_normal_map.hpp"

namespace slam_mms {

using Clock = std::chrono::steady_clock;

inline double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

namespace internal {

/// The scan de-skewed to its start (lidar frame) and its range image (step 1); registration masks
/// moving objects out of both (step 4). Reused across scans.
struct DeskewedScan {
  PointCloud cloud;
  VertexNormalMap vnm;
};

struct ScanStep {
  Eigen::Isometry3d T_world_submap = Eigen::Isometry3d::Identity();  ///< The current submap's.
  Eigen::Vector3d g_submap = Eigen::Vector3d::Zero();                ///< Gravity in the submap.
  bool is_reference = false;  ///< The scan is its submap's reference (first scan).
  Prediction pred;            ///< 2. predict
  /// 1. de-skew: the body motion over the scan it was de-skewed with (T_bstart_bend), and
  /// whether that came from the constant-velocity model (no POS, no IMU).
  Eigen::Isometry3d T_bstart_bend = Eigen::Isometry3d::Identity();
  bool constant_velocity_deskew = false;
  Eigen::Isometry3d T_world_lidar_pred = Eigen::Isometry3d::Identity();  ///< 3. render
  bool have_model = false;                                               ///< 3. render
  std::optional<Eigen::Isometry3d> T_submap_reg;  ///< 4. register: the usable result
  Matrix6d cov_reg = Matrix6d::Identity();        ///< 4. register: its covariance
  StateId cur_state = 0;                          ///< 5. factors: the scan's window state
  Eigen::Isometry3d T_submap_cur = Eigen::Isometry3d::Identity();  ///< 6. optimize
};

}  // namespace internal
}  // namespace slam_mms
