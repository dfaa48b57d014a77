#pragma once
// SubmapGraph: the level-2 global factor graph (paper §5.2, Fig. 4 right, eqs 20-25) on Ceres.
//
// Nodes are submaps, each with its reference pose T_world_submap (the pose of its first scan,
// X_Nref) and the poses T_submap_scan of its scans, which level 1 estimated and level 2 keeps
// rigid: after every solve each scan pose is T_world_scan = T_world_submap * T_submap_scan.
//
// Factors (eq 25: argmin sum |r_GNSS|^2 + |r_Reckon|^2 + |r_Reg|^2 + |r_Loop|^2):
//  - AddRegistrationFactor: map-to-map registration of submap b against a (F_Reg, §5.2.1).
//  - AddReckonFactor: the serial scan-to-map chain T~ = T_Nref_Nlast * T_Nlast_(N+1)first (eq 21).
//  - AddLoopFactor: loop closure (eqs 22-23), always robustified by Options::loop_loss so one bad
//    loop cannot bend the map. The default Cauchy scale of 5 sigma (about sqrt of the 6-DoF 99.9 %
//    chi-square quantile) keeps a correct loop after a long drift (its whitened residual may be
//    hundreds of sigmas at the start, but it agrees with the chain between its ends) while a loop
//    that contradicts the chain costs less left unsatisfied than followed (see docs/backend.md).
//    Each loop is also compared with the sequential chain between its ends (composed from the
//    reckon/registration factors between consecutive submaps); the Mahalanobis distance comes back
//    in LoopCheck (CheckLoop() gives it before adding, for the caller's verification).
//  - AddGnssPrior: a GNSS antenna position on a scan of a submap (eq 24; the ins module's
//    GnssPositionFactor with the lever arm folded into the submap frame). Plug and play: add it
//    only for valid fixes; the graph works with none (then the first submap is held fixed as the
//    gauge). Fixes may share a GNSS bias (AddGnssBias): a constant offset of their datum, e.g. one
//    per drive in the multi-drive adjustment.
// Factors() gives every factor back as it was added, so a graph can be written out and rebuilt.
//
// Solving: batch Levenberg-Marquardt (<= Options::max_iterations), warm-started from the current
// estimate. The orchestration decides when (§5.2.3) and says why with SolveTrigger. Solve time is
// bounded as the graph grows: unless the trigger is kFinish, only the newest
// Options::active_submaps nodes plus the nodes spanned by loops added since the last solve (from
// the older loop end to the newest node) and, for kGnssReturned, the nodes since the last
// GNSS-anchored node before the outage are free; all others are held constant; a wall-time cap
// bounds the rest. See docs/backend.md.
//
// Ownership: move-only (pimpl). Thread safety: none; one thread at a time (Solve uses
// Options::num_threads threads internally).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "slam_mms/backend/robust_loss.hpp"
#include "slam_mms/backend/solve_summary.hpp"
#include "slam_mms/backend/submap_graph_factor.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms {

/// Why the orchestration asks for a global solve (paper §5.2.3).
enum class SolveTrigger {
  kGnssReturned,  ///< GNSS is back after a long outage: free the outage segment.
  kLoopClosed,    ///< A loop factor was added: free the loop.
  kFinish,        ///< End of the drive: solve the whole graph.
  kRequested,     ///< Any other reason: the recent window (plus pending loops).
};

const char* SolveTriggerName(SolveTrigger trigger);

/// A scan pose, in the submap frame and (after a solve) in the world.
struct SubmapScanPose {
  SubmapId submap = 0;
  int64_t scan_id = 0;
  Timestamp stamp;
  Eigen::Isometry3d T_submap_scan = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_world_scan = Eigen::Isometry3d::Identity();
};

/// How a loop measurement compares with the sequential chain between its two submaps.
struct LoopCheck {
  bool chain_available =
      false;  ///< Every consecutive pair between a and b has a sequential factor.
  Eigen::Isometry3d T_a_b_chain = Eigen::Isometry3d::Identity();  ///< Chain prediction.
  Matrix6d chain_covariance = Matrix6d::Zero();                   ///< Its covariance.
  double mahalanobis_sq = 0.0;  ///< e^T (Sigma_loop + Sigma_chain)^-1 e, e = loop vs chain (6 DoF).
};

/// A loop-closure candidate (the caller registers and verifies it, e.g. with ICP).
struct LoopCandidate {
  SubmapId submap = 0;
  double distance_m = 0.0;  ///< From the query position to the nearest pose of the submap.
};

/// The conditional model of two correlated attitude errors for SubmapGraph::
/// AddAttitudeChainFactor, in world axes: eps_b = transition * eps_a + w, w ~ N(0, covariance).
struct AttitudeChain {
  Eigen::Matrix3d transition = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();  ///< [rad^2]
};
/// Q is never below this share of b's marginal covariance (the measured relative attitude is
/// never exact).
inline constexpr double kAttitudeChainMinInnovationShare = 1e-4;
/// From the joint covariance of the two errors as a filter states them: cov_a, cov_b (right
/// perturbations in the body axes of R_world_a, R_world_b, rad^2) and cross_ba = Cov(e_b, e_a):
/// A = C_ba C_aa^-1, Q = C_bb - A C_ab (world axes) plus the floor. InvalidArgument where the
/// joint covariance is not positive definite (a correlation above 1).
StatusOr<AttitudeChain> AttitudeChainFromCrossCovariance(const Eigen::Matrix3d& R_world_a,
                                                         const Eigen::Matrix3d& cov_a,
                                                         const Eigen::Matrix3d& R_world_b,
                                                         const Eigen::Matrix3d& cov_b,
                                                         const Eigen::Matrix3d& cross_ba);
/// A first-order Gauss-Markov error with marginal covariances cov_a, cov_b (body axes as above)
/// and correlation rho in [0, 1] (exp(-dt / tau)): u = Sigma^-1/2 eps (symmetric roots, world
/// axes) follows u_b = rho u_a + sqrt(1 - rho^2) w: A = rho Sigma_b^1/2 Sigma_a^-1/2,
/// Q = max(1 - rho^2, floor) Sigma_b.
StatusOr<AttitudeChain> GaussMarkovAttitudeChain(const Eigen::Matrix3d& R_world_a,
                                                 const Eigen::Matrix3d& cov_a,
                                                 const Eigen::Matrix3d& R_world_b,
                                                 const Eigen::Matrix3d& cov_b, double rho);

class SubmapGraph {
 public:
  struct Options {
    int max_iterations = 100;          ///< Levenberg-Marquardt iterations (paper: <= 100), > 0.
    double max_solve_time_s = 5.0;     ///< Wall-time cap of one solve [s], > 0.
    int num_threads = 2;               ///< Ceres threads, > 0.
    double function_tolerance = 1e-8;  ///< Ceres relative cost change to stop, > 0.
    /// Newest nodes free in a bounded solve (kFinish frees all), > 0.
    int active_submaps = 50;
    /// Robust loss of loop factors (scale in sigmas of the loop's whitened residual, see above).
    RobustLoss loop_loss = RobustLoss::Cauchy(5.0);
    /// Robust loss of GNSS priors (multipath).
    RobustLoss gnss_loss = RobustLoss::Huber(3.0);
    /// Loop candidates: nearer than this to the query [m] (the paper's D_thr), > 0.
    double loop_candidate_distance_m = 20.0;
    /// Loop candidates: at least this many submaps older than the query submap, >= 1.
    int loop_min_submap_gap = 3;

    [[nodiscard]] Status Validate() const;
  };

  static StatusOr<SubmapGraph> Create(const Options& options);
  static StatusOr<SubmapGraph> Create();

  SubmapGraph(SubmapGraph&&) noexcept;
  SubmapGraph& operator=(SubmapGraph&&) noexcept;
  SubmapGraph(const SubmapGraph&) = delete;
  SubmapGraph& operator=(const SubmapGraph&) = delete;
  ~SubmapGraph();

  /// Adds submap `id` (greater than every id added before) with its reference pose.
  Status AddSubmap(SubmapId id, const Eigen::Isometry3d& T_world_submap);

  /// Records a scan of submap `id` with its pose in the submap frame (from level 1).
  Status AddScan(SubmapId id, int64_t scan_id, Timestamp stamp,
                 const Eigen::Isometry3d& T_submap_scan);

  /// Replaces the scan poses of submap `id` (level 1 may refine them until the submap closes).
  Status SetScans(SubmapId id, const std::vector<SubmapScanPose>& scans);

  /// F_Reg: T~_a_b from map-to-map registration, covariance rotation first.
  Status AddRegistrationFactor(SubmapId a, SubmapId b, const Eigen::Isometry3d& T_a_b,
                               const Matrix6d& covariance,
                               const RobustLoss& loss = RobustLoss::Huber(3.0));
  /// F_Reckon (eq 21): T~_a_b from the serial scan-to-map chain.
  Status AddReckonFactor(SubmapId a, SubmapId b, const Eigen::Isometry3d& T_a_b,
                         const Matrix6d& covariance);
  /// F_Loop (eqs 22-23), robustified by Options::loop_loss (scale adapted, see above).
  StatusOr<LoopCheck> AddLoopFactor(SubmapId a, SubmapId b, const Eigen::Isometry3d& T_a_b,
                                    const Matrix6d& covariance);
  /// The comparison AddLoopFactor would make, without adding anything.
  StatusOr<LoopCheck> CheckLoop(SubmapId a, SubmapId b, const Eigen::Isometry3d& T_a_b,
                                const Matrix6d& covariance) const;
  /// F_GNSS (eq 24): antenna position p~_world_antenna (3x3 covariance) measured when the body was
  /// at T_submap_body in submap `id`, antenna at t_body_antenna (lever arm) in the body frame.
  /// A 6-DoF prior on a submap reference (residual as PosePriorFactor: rotation first, in the
  /// submap's body axes). With large variances on yaw and translation it is an attitude prior: the
  /// roll and pitch that level 1 observed from gravity, which GNSS positions alone cannot observe
  /// on straight roads (a rotation about the direction of travel moves no position).
  Status AddPosePrior(SubmapId id, const Eigen::Isometry3d& T_world_submap,
                      const Matrix6d& covariance);
  /// Attitudes R~_world_a and R~_world_b of submaps a and b (a added before b) measured by one
  /// source whose errors are correlated (a POS): in world axes, eps = Log(R R~^T), b's error given
  /// a's is eps_b = A eps_a + w, w ~ N(0, Q) (`chain`: AttitudeChainFromCrossCovariance,
  /// GaussMarkovAttitudeChain). A chain of them behind one AddPosePrior on the first submap is the
  /// measurements' joint density as a Markov chain (backend/attitude_chain_factor.hpp; A = 0 is
  /// an independent prior, A -> I with Q -> 0 the measured relative attitude).
  Status AddAttitudeChainFactor(SubmapId a, SubmapId b, const Eigen::Matrix3d& R_world_a,
                                const Eigen::Matrix3d& R_world_b, const AttitudeChain& chain);
  /// `gnss_bias` >= 0: the fix measures p_antenna + b with b the bias of that key (added before
  /// with AddGnssBias); -1: no bias.
  Status AddGnssPrior(SubmapId id, const Eigen::Vector3d& p_world_antenna,
                      const Eigen::Matrix3d& covariance,
                      const Eigen::Isometry3d& T_submap_body = Eigen::Isometry3d::Identity(),
                      const Eigen::Vector3d& t_body_antenna = Eigen::Vector3d::Zero(),
                      int gnss_bias = -1);
  /// A GNSS bias `key` (>= 0, new): an unknown constant world offset b [m] of the fixes added
  /// with it, with a zero-mean prior of `prior_covariance` [m^2]. Free in every solve.
  Status AddGnssBias(int key, const Eigen::Matrix3d& prior_covariance);
  /// A GNSS bias `key` (>= 0, new) that follows bias `from_key` as a Gauss-Markov process: b =
  /// transition * b_from + w, w ~ N(0, covariance) [m^2], transition in [0, 1] (exp(-dt / tau)
  /// for the time dt between the two; the stationary covariance S then gives covariance =
  /// (1 - transition^2) S). Free in every solve; starts at transition * b_from.
  Status AddGnssBiasLink(int from_key, int key, double transition,
                         const Eigen::Matrix3d& covariance);
  /// The current estimate of bias `key` (NotFound where never added).
  StatusOr<Eigen::Vector3d> GnssBias(int key) const;
  /// Every factor in the order it was added (a loop's covariance as given, before loop_loss).
  const std::vector<SubmapGraphFactor>& Factors() const;

  /// How a factor fits the current estimate (FitFactors).
  struct FactorFit {
    double chi2 = 0.0;  ///< Squared whitened residual, the robust loss not applied.
    int dim = 0;        ///< Residual dimension.
    /// Redundancy number: the share of its dim residual directions the estimate does not absorb,
    /// in [0, dim] (tr(I - J_f (J^T J)^-1 J_f^T), whitened; E[chi2] = redundancy where its
    /// covariance is right). A factor alone on its parameters has 0, one of many agreeing
    /// measurements of them close to dim.
    double redundancy = 0.0;
  };
  /// Per factor of Factors() (same order), at the current estimate (after Solve), with the nodes
  /// the last solve left free; for variance component estimation (sum chi2 / sum redundancy of a
  /// group of factors is its variance factor). FailedPrecondition where the free nodes are not
  /// all observed (singular normal matrix).
  StatusOr<std::vector<FactorFit>> FitFactors() const;

  /// Batch LM (eq 25), then every scan pose follows its submap.
  StatusOr<SolveSummary> Solve(SolveTrigger trigger);

  /// Submaps within Options::loop_candidate_distance_m of p_world (nearest pose of each submap:
  /// reference and scans), at least Options::loop_min_submap_gap submaps older than `current`,
  /// nearest first.
  std::vector<LoopCandidate> LoopCandidates(const Eigen::Vector3d& p_world, SubmapId current) const;

  bool HasSubmap(SubmapId id) const;
  std::vector<SubmapId> SubmapIds() const;
  StatusOr<Eigen::Isometry3d> SubmapPose(SubmapId id) const;
  /// Marginal covariance of a submap pose (rotation first, right perturbation), over the whole
  /// graph.
  StatusOr<Matrix6d> SubmapCovariance(SubmapId id) const;
  /// Every scan of every submap, in submap then scan order, with T_world_scan up to date.
  std::vector<SubmapScanPose> ScanPoses() const;

  int num_submaps() const;
  int num_loop_factors() const;
  int num_gnss_priors() const;
  /// Nodes left free in the last solve.
  int last_num_free_submaps() const;
  const Options& options() const;

 private:
  struct Impl;
  explicit SubmapGraph(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
