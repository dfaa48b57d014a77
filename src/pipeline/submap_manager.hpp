#pragma once
// SubmapManager: level 2 of the hierarchical factor graph (paper §5.2, Fig. 4 right, eqs 20-25) on
// top of the backend's SubmapGraph: for each submap that level 1 finishes it adds the reckon factor
// (F_Reckon, eq 21), map-to-map registration with the previous submap (F_Reg, PointIcp, §5.2.1),
// GNSS position priors (F_GNSS, eq 24, only where fixes were used) and searches loops (F_Loop, eqs
// 22-23: candidates within loop_distance_m that are not recent, verified by registration: inlier
// ratio, residual and agreement with the graph); solves after GNSS returns from a long outage, on a
// loop and on Finish(), then moves every submap (and so every scan pose, T_world_scan =
// T_world_submap * T_submap_scan).
//
// Ownership: owns the graph and its registration workspace. Thread safety: not thread-safe.

#include <Eigen/Geometry>
#include <memory>
#include <optional>
#include <vector>

#include "registration/point_icp.hpp"
#include "slam_mms/backend/submap_graph.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/pipeline/level2_options.hpp"
#include "slam_mms/pipeline/submap_source.hpp"

namespace slam_mms {

class SubmapManager {
 public:
  using Options = Level2Options;
  using Stats = Level2Stats;
  /// `num_threads` (>= 1): the graph solve's and the map-to-map registration's threads.
  static StatusOr<std::unique_ptr<SubmapManager>> Create(const Options& options,
                                                         int num_threads = 2);
  ~SubmapManager();
  /// A GNSS measurement that the POS used (antenna position in world; lever arm in the factor).
  void AddGnssMeasurement(const GnssMeasurement& measurement,
                          const Eigen::Vector3d& t_body_antenna);
  /// Level 1 finished `submap_id` (read from `submaps`, which level 2 never changes): add its
  /// factors, test loops, solve when triggered. Returns the new estimates of level 1's submaps
  /// after a usable solve (the unfinished current one moved rigidly with the last finished one),
  /// in `submaps` order, for the host to apply (Localizer::SetSubmapPose); empty without a solve.
  /// `pos_attitude` (may be absent): the submap frame's attitude from the POS and its 3x3 rotation
  /// covariance (right perturbation, submap axes, rad^2) for the attitude prior (yaw included).
  struct PosAttitude {
    Eigen::Matrix3d R_world_submap = Eigen::Matrix3d::Identity();
    Eigen::Matrix3d cov_rotation = Eigen::Matrix3d::Identity();
    /// The POS's own model of this attitude's error given the one it gave for submap
    /// `previous_submap` (Options::pos_attitude_cross_covariance); absent: none.
    struct Link {
      int32_t previous_submap = -1;
      AttitudeChain chain;
    };
    std::optional<Link> link;
  };
  StatusOr<std::vector<SubmapPoseUpdate>> OnSubmapFinished(
      const SubmapSource& submaps, int32_t submap_id, bool gnss_returned_after_outage,
      const std::optional<PosAttitude>& pos_attitude = std::nullopt);
  /// The final solve; its estimates as for OnSubmapFinished.
  StatusOr<std::vector<SubmapPoseUpdate>> Finish(const SubmapSource& submaps);
  const Stats& stats() const;
  /// The level-2 graph (its factors for DriveResult).
  const SubmapGraph& graph() const;

 private:
  SubmapManager();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
