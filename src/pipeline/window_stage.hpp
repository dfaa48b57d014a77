#pragma once
// WindowStage: steps 5 and 6 of Localizer::ProcessScan, level 1's local window (paper §5.1,
// Fig. 4 left). One SlidingWindowGraph per submap, in the submap's frame, whose kept reference
// state is the submap's first scan; per scan:
//   5. add factors  a state for the scan, the motion factor from the previous scan's state
//                   (F_Odom eq 12, F_Prein eq 14, or the constant-velocity factor of LiDAR-only
//                   mode) and F_Reg (eq 16) from the reference, checked against the motion
//                   prediction (Graham et al. 2015);
//   6. optimize     Levenberg-Marquardt over the window; the scan's pose, velocity, biases and
//                   pose covariance.
//
// Ownership: owns the window and the state ids (the reference's, the previous scan's, the next
// free one); the previous scan's optimized values (PreviousScan) are the caller's and handed in.
// Thread safety: not thread-safe.

#include <Eigen/Geometry>
#include <memory>

#include "backend/sliding_window_graph.hpp"
#include "pipeline/motion_prior.hpp"
#include "pipeline/scan_step.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/localizer.hpp"

namespace ceres {
class CostFunction;
}

namespace slam_mms::internal {

/// A prior x ~ N(mean, sigma^2 I) on a block of size N, as a ceres::NormalPrior.
std::unique_ptr<ceres::CostFunction> MakeNormalPrior(const Eigen::VectorXd& mean,
                                                     const Eigen::VectorXd& sigma);

class WindowStage {
 public:
  WindowStage() = default;
  /// Uses options.window, num_threads, mode (IMU states in full mode) and the odom / cv sigmas.
  explicit WindowStage(const Localizer::Options& options);

  /// A new window (a new submap) whose reference state, held at the identity pose, gets the
  /// velocity v_submap and the biases `bias` (priors on both, with IMU states).
  Status Start(const Eigen::Vector3d& v_submap, const Vector6d& bias);

  /// Step 5: sets step->cur_state (the reference's for a reference scan, else a new state at the
  /// registration or the prediction) and adds its motion factor and F_Reg; the consistency
  /// check's outcome and the time go into `res`.
  Status AddFactors(const Scan& scan, const ScanMotionInput& motion, const PreviousScan& prev,
                    ScanStep* step, LocalizationResult* res);

  /// Step 6: solves the window and sets step->T_submap_cur and res->cov_T_world_body; with IMU
  /// states the optimized velocity and biases go into prev->v_submap and prev->bias.
  Status Optimize(const Scan& scan, ScanStep* step, PreviousScan* prev, LocalizationResult* res);

  /// The scan in state `state` is now the previous one (the next motion factor starts there).
  void Advance(StateId state) { prev_id_ = state; }

  bool use_imu_states() const { return use_imu_states_; }
  StateId reference_id() const { return ref_id_; }
  StateId previous_id() const { return prev_id_; }
  const SlidingWindowGraph* graph() const { return window_.get(); }

 private:
  /// The motion factor between the previous scan's state and `cur_state`; returns its covariance
  /// (what F_Reg is checked against).
  StatusOr<Matrix6d> AddMotionFactor(StateId cur_state, const ScanMotionInput& motion,
                                     const PreviousScan& prev, const ScanStep& step, double dt);

  SlidingWindowGraph::Options window_options_;
  double odom_sigma_rot_rad_ = 0.0;
  double odom_sigma_trans_m_ = 0.0;
  double cv_sigma_rot_rad_ = 0.0;
  double cv_sigma_trans_m_ = 0.0;
  bool use_imu_states_ = false;
  std::unique_ptr<SlidingWindowGraph> window_;
  StateId next_id_ = 0;
  StateId ref_id_ = 0;
  StateId prev_id_ = 0;
  /// Registrations in a row that failed the consistency gate (rejected, or taken down-weighted
  /// in recovery: noise::kRejectedRegistrationsBeforeRecovery), across submaps.
  int rejected_in_a_row_ = 0;
};

}  // namespace slam_mms::internal
