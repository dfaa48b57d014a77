#pragma once
// SlidingWindowGraph: the level-1 local factor graph (paper §5.1, Fig. 4 left) on Ceres.
//
// States are the scans in the current window, keyed by a caller-chosen, strictly increasing
// StateId (e.g. the scan index). Each state has a pose T_frame_body (one 7-double block, see
// backend/pose_block.hpp) and, where IMU preintegration factors are used, a velocity (3) and
// IMU biases (6, [ba, bg]). `frame` is whatever frame the caller works in (the Localizer uses the
// world frame or the frame of the current submap, eqs 12/16).
//
// Factors:
//  - AddRelativePoseFactor: the between factor of eqs 12 (F_Odom, kind kMotion), 16 (F_Reg, kind
//    kRegistration) and small loops inside a submap (kLoop), each with its own robust loss.
//  - AddPosePrior: a 6-DoF prior (anchor the first state, or the submap reference).
//  - AddCostFunction: any ceres::CostFunction on state blocks, e.g. the ins module's
//    ImuPreintegrationFactor (eq 14) on (pose_i, v_i, bias_i, pose_j, v_j, bias_j).
//
// Consistency checking (Graham et al. 2015): a kRegistration factor is compared with the motion
// prediction of the same relative pose (the caller's MotionPrediction, or else the kMotion factors
// between the two states, directly or chained through consecutive states). When the squared
// Mahalanobis distance d2 = e^T (Sigma_reg + Sigma_pred)^-1 e exceeds the chi-square gate, the
// registration is rejected or down-weighted (its covariance inflated by d2 / gate), and counted;
// a caller's prediction with `enforce` false only reports the check.
//
// Window: after each Solve(), while more than Options::window_size non-kept states remain, the
// oldest leaves the window. Options::exit_mode kMarginalize (default) folds the factors of the
// leaving state into a Gaussian prior on its neighbours by the Schur complement (no information
// lost, up to linearisation); kFix holds it constant and drops it once it has no factor to a free
// state (information about its uncertainty is lost: the window becomes over-confident). See
// docs/backend.md. States added with `keep = true` (e.g. the submap reference of eq 12) never leave
// automatically; RemoveState() removes any state the same way.
//
// Every input is validated before it reaches Ceres (finite values, positive-definite covariances,
// known state ids, matching block sizes) and comes back as a Status; a failed solve comes back in
// the SolveSummary.
//
// Ownership: move-only (pimpl); owns the Ceres problem and every cost function handed to it.
// Thread safety: none; use one graph from one thread at a time (Solve uses Options::num_threads
// threads internally).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "slam_mms/backend/robust_loss.hpp"
#include "slam_mms/backend/sliding_window_options.hpp"
#include "slam_mms/backend/solve_summary.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/status.hpp"

namespace ceres {
class CostFunction;
}

namespace slam_mms {

using StateId = int64_t;
using FactorId = int64_t;

/// Which block of a state a cost function's parameter block is.
enum class StateBlock { kPose, kVelocity, kBias };

struct StateBlockRef {
  StateId state = 0;
  StateBlock block = StateBlock::kPose;
};

/// Role of a relative-pose factor; only kRegistration factors are consistency-checked, and only
/// kMotion factors serve as the motion prediction.
enum class FactorKind { kMotion, kRegistration, kLoop };

/// Initial values of a new state.
struct StateInit {
  Eigen::Isometry3d T_frame_body = Eigen::Isometry3d::Identity();
  /// With a value, the state gets a velocity block [m/s, in frame]. Needed by preintegration.
  std::optional<Eigen::Vector3d> v_frame;
  /// With a value, the state gets a bias block [ba (m/s^2), bg (rad/s)].
  std::optional<Vector6d> imu_bias;
  /// Kept states are never removed by the window (e.g. the submap reference X_Nref of eq 12).
  bool keep = false;
};

/// A prediction of T_a_b with covariance (library convention), e.g. from IMU preintegration.
/// `enforce` false: the registration is still checked and the outcome reports it, but it is added
/// as it is even when it fails the gate (the host has concluded that the prediction is what is
/// off; counted in ConsistencyStats::taken_inconsistent).
struct MotionPrediction {
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Identity();
  bool enforce = true;
};

/// What happened to a relative-pose factor handed to the graph.
struct FactorOutcome {
  std::optional<FactorId> id;        ///< Empty when the factor was rejected.
  bool consistency_checked = false;  ///< A prediction was available and the gate was applied.
  bool consistent = true;            ///< d2 <= gate (true when not checked).
  double mahalanobis_sq = 0.0;       ///< d2 of the check (0 when not checked).
  double covariance_scale = 1.0;     ///< > 1 when down-weighted.
};

/// Running counts of the consistency check (Graham et al. 2015).
struct ConsistencyStats {
  int checked = 0;
  int passed = 0;
  int rejected = 0;
  int down_weighted = 0;
  int taken_inconsistent = 0;  ///< Failed the gate, added as it is (MotionPrediction::enforce).
  int unchecked = 0;           ///< Registrations with no motion prediction to compare with.
};

class SlidingWindowGraph {
 public:
  using ExitMode = WindowExitMode;
  using InconsistencyAction = WindowInconsistencyAction;

  /// The SDK's options (SlidingWindowOptions) plus the thread count its owner sets.
  struct Options : SlidingWindowOptions {
    int num_threads = 2;  ///< Ceres threads, > 0.
    [[nodiscard]] Status Validate() const;
  };

  static StatusOr<SlidingWindowGraph> Create(const Options& options);
  static StatusOr<SlidingWindowGraph> Create();

  SlidingWindowGraph(SlidingWindowGraph&&) noexcept;
  SlidingWindowGraph& operator=(SlidingWindowGraph&&) noexcept;
  SlidingWindowGraph(const SlidingWindowGraph&) = delete;
  SlidingWindowGraph& operator=(const SlidingWindowGraph&) = delete;
  ~SlidingWindowGraph();

  /// Adds state `id` (must be greater than every id added before).
  Status AddState(StateId id, const StateInit& init);

  /// 6-DoF prior on the pose of `id` (covariance rotation first, right perturbation).
  StatusOr<FactorId> AddPosePrior(StateId id, const Eigen::Isometry3d& T_frame_body,
                                  const Matrix6d& covariance,
                                  const RobustLoss& loss = RobustLoss::None());

  /// Between factor T~_a_b (eqs 12/16/23). kRegistration factors are consistency-checked against
  /// `prediction` or, when empty, the kMotion factors between a and b.
  StatusOr<FactorOutcome> AddRelativePoseFactor(
      StateId a, StateId b, const Eigen::Isometry3d& T_a_b, const Matrix6d& covariance,
      FactorKind kind, const RobustLoss& loss = RobustLoss::None(),
      const std::optional<MotionPrediction>& prediction = std::nullopt);

  /// Any cost function on state blocks (sizes must match: pose 7, velocity 3, bias 6). The graph
  /// takes ownership.
  StatusOr<FactorId> AddCostFunction(std::unique_ptr<ceres::CostFunction> cost,
                                     const std::vector<StateBlockRef>& blocks,
                                     const RobustLoss& loss = RobustLoss::None());

  /// Removes one factor (e.g. one found wrong later). NotFound if unknown.
  Status RemoveFactor(FactorId id);

  /// Holds a block constant or frees it again (e.g. biases calibrated in advance, as in the paper).
  Status SetBlockConstant(StateBlockRef block, bool constant);

  /// Levenberg-Marquardt on the window, then the window update (marginalize / fix old states).
  /// Status only for a broken graph state; solver failures are in the summary.
  StatusOr<SolveSummary> Solve();

  /// Removes `id` from the window now, by the configured exit mode.
  Status RemoveState(StateId id);

  bool HasState(StateId id) const;
  /// Ids of the states in the window (ascending), kept ones included.
  std::vector<StateId> StateIds() const;
  StatusOr<Eigen::Isometry3d> Pose(StateId id) const;
  StatusOr<Eigen::Vector3d> Velocity(StateId id) const;
  StatusOr<Vector6d> ImuBias(StateId id) const;

  /// Overwrites a state's pose (e.g. after re-anchoring); the marginal prior is not moved.
  Status SetPose(StateId id, const Eigen::Isometry3d& T_frame_body);

  /// Marginal covariance of the pose of `id` given every factor in the window (including the
  /// marginalization prior), rotation first, right perturbation. FailedPrecondition when the
  /// graph does not constrain the pose (gauge freedom) or Ceres cannot compute it.
  StatusOr<Matrix6d> PoseCovariance(StateId id) const;

  const ConsistencyStats& consistency_stats() const;
  int num_factors() const;
  int num_marginalized_states() const;
  const Options& options() const;

 private:
  struct Impl;
  explicit SlidingWindowGraph(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
