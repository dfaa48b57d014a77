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

#include "slam_mms/core/status.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/pipeline/extrinsic_calibration_options.hpp"
#include "slam_mms/pipeline/submap_source.hpp"
#include "slam_mms/registration/point_icp.hpp"

namespace slam_mms {

class SubmapManager {
 public:
  struct Options {
    bool enabled = true;
    bool use_map_to_map = true;
    bool use_gnss = true;
    bool use_loops = true;
    double loop_distance_m = 25.0;  ///< D_thr [m].
    int loop_min_submap_gap = 6;    ///< Candidates at least this many submaps back.
    double loop_min_inlier_ratio = 0.5;
    double loop_max_rms_m = 0.25;
    double loop_gate_chi2 = 50.0;  ///< Agreement with the graph (loose: drift is expected).
    double long_outage_s = 10.0;   ///< GNSS back after at least this long: solve.
    double reckon_sigma_rot_rad = 0.002;
    double reckon_sigma_trans_m = 0.05;
    double gnss_sigma_scale = 1.0;  ///< Multiplies the GNSS measurement covariance.
    /// GNSS errors are time-correlated (an RTK-float or single-point bias wanders over tens of
    /// seconds), so fixes at 10 Hz are not independent: the fixes within this window [s] count as
    /// one, i.e. each fix's covariance is multiplied by window / (time since the previous fix),
    /// at least 1. 0 treats every fix as independent. >= 0. On the default drive with a 60 s
    /// outage, 10 s brings the largest error in the outage from 0.81 to 0.45 m (docs/results.md).
    double gnss_correlation_s = 10.0;
    /// With GNSS: an attitude prior on each submap reference. Where the POS attitude is given
    /// (OnSubmapFinished's `pos_attitude`), the prior is the POS's roll, pitch and yaw with the
    /// POS's own covariance: a weaker prior let the GNSS noise rotate the submaps where the
    /// motion holds no rotation information (standing, stop-and-go: 0.19 deg of pitch error
    /// against the POS's 0.01 on a sweep drive; a free yaw turned standing drives by 2-13 deg,
    /// docs/sweep.md). Else level 1's roll and pitch with this sigma [rad] and a free yaw. 0
    /// disables the prior.
    double attitude_prior_sigma_rad = 0.0175;
    int max_iterations = 100;
    int num_threads = 2;
    /// Boresight self-calibration before the run (slam_mms_run --calibrate-extrinsics): the
    /// LiDAR's extrinsic and clock offset estimated against the offline POS (CalibrateExtrinsics,
    /// docs/calibration.md) and the run made with the estimate. Read by the hosts that own a
    /// whole drive (slam_mms_run); a streaming MappingSystem cannot make the second pass and
    /// ignores it. Off until measured to help (docs/calibration.md).
    bool estimate_extrinsics = false;
    /// Its options (num_threads is taken from MappingSystem::Options::num_threads).
    ExtrinsicCalibrationOptions extrinsic_calibration;
    PointIcp::Options icp;
    [[nodiscard]] Status Validate() const;
  };
  struct Stats {
    int solves = 0;
    int loops_tested = 0;
    int loops_accepted = 0;
    int map_to_map_accepted = 0;
    int gnss_factors = 0;
    double last_solve_ms = 0.0;
  };
  static StatusOr<std::unique_ptr<SubmapManager>> Create(const Options& options);
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
  };
  StatusOr<std::vector<SubmapPoseUpdate>> OnSubmapFinished(
      const SubmapSource& submaps, int32_t submap_id, bool gnss_returned_after_outage,
      const std::optional<PosAttitude>& pos_attitude = std::nullopt);
  /// The final solve; its estimates as for OnSubmapFinished.
  StatusOr<std::vector<SubmapPoseUpdate>> Finish(const SubmapSource& submaps);
  const Stats& stats() const;

 private:
  SubmapManager();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
