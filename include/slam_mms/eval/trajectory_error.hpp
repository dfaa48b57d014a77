#pragma once
// Absolute trajectory error (ATE) of an estimated trajectory against a ground truth: RMSE of the
// position differences per axis and in 3D, and rotation RMSE per roll/pitch/yaw and in total
// (paper §6, Table 1).
//
// Matching ("compare in one frame, at one time", ARCHITECTURE.md): every estimated pose is compared
// with the ground truth INTERPOLATED at that pose's exact stamp (Trajectory::Interpolate); poses
// outside the ground truth's span, or inside a ground-truth gap longer than
// MatchOptions::max_ground_truth_gap_s, are skipped and counted. No alignment is applied by
// default: a geo-referenced system is judged in the frame it claims. SE(3) or Sim(3) Umeyama
// alignment is an option for "shape" numbers and is labelled so in the result.
//
// Thread safety: free functions on value types; safe to call concurrently.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/eval/umeyama.hpp"

namespace slam_mms::eval {

struct MatchOptions {
  /// Largest gap between the two ground-truth samples bracketing an estimated stamp across which
  /// the ground truth is interpolated [s]; estimated poses in longer gaps are skipped.
  double max_ground_truth_gap_s = 1.0;
  /// Estimated stamps this close outside the ground truth's span take its end pose [s].
  double end_tolerance_s = 1e-6;

  [[nodiscard]] Status Validate() const;
};

/// Estimated poses paired with the ground truth interpolated at their stamps, in time order.
struct MatchedPoses {
  std::vector<Timestamp> stamps;
  std::vector<Eigen::Isometry3d> T_world_est;
  std::vector<Eigen::Isometry3d> T_world_gt;
  size_t num_unmatched = 0;  ///< Estimated poses with no ground truth at their stamp.

  size_t size() const { return stamps.size(); }
};

/// Pairs every estimated pose with the ground truth interpolated at its stamp. Fails where either
/// trajectory is empty, options are invalid, or no pose could be matched.
StatusOr<MatchedPoses> MatchByTimestamp(const Trajectory& estimate, const Trajectory& ground_truth,
                                        const MatchOptions& options = MatchOptions());

enum class Alignment {
  kNone,  ///< Compare as given (the default for geo-referenced outputs).
  kSe3,   ///< Umeyama rotation + translation of the estimate onto the ground truth.
  kSim3,  ///< Umeyama rotation + translation + scale (monocular-style outputs).
};

/// "none", "se3", "sim3".
const char* AlignmentName(Alignment alignment);

struct AteOptions {
  Alignment alignment = Alignment::kNone;
  MatchOptions match;

  [[nodiscard]] Status Validate() const;
};

/// The error of one matched pose (after alignment, if any).
struct PoseError {
  Timestamp stamp;
  Eigen::Vector3d p_est_world = Eigen::Vector3d::Zero();  ///< Estimated position (aligned) [m].
  Eigen::Vector3d p_gt_world = Eigen::Vector3d::Zero();   ///< Ground-truth position [m].
  Eigen::Vector3d position_error_world = Eigen::Vector3d::Zero();  ///< p_est - p_gt [m].
  double position_error_m = 0.0;                                   ///< |p_est - p_gt| [m].
  /// Roll, pitch, yaw of the estimate minus those of the ground truth, wrapped to (-pi, pi] [rad].
  Eigen::Vector3d rpy_error_rad = Eigen::Vector3d::Zero();
  /// Angle of R_gt^T * R_est [rad], in [0, pi].
  double rotation_error_rad = 0.0;
};

struct AteResult {
  Alignment alignment = Alignment::kNone;
  /// The transform applied to the estimate (identity, scale 1 for kNone): p' = s R p + t.
  SimilarityTransform T_gt_est;
  size_t num_matched = 0;
  size_t num_unmatched = 0;

  double ate_rmse_m = 0.0;  ///< sqrt(mean |p_est - p_gt|^2).
  Eigen::Vector3d ate_rmse_xyz_m =
      Eigen::Vector3d::Zero();  ///< Per world axis (x east, y north, z up).
  double ate_mean_m = 0.0;
  double ate_median_m = 0.0;
  double ate_max_m = 0.0;
  double rot_rmse_deg = 0.0;  ///< RMSE of the angle of R_gt^T R_est.
  Eigen::Vector3d rot_rmse_rpy_deg =
      Eigen::Vector3d::Zero();  ///< RMSE of the roll/pitch/yaw differences.
  /// Mean of the roll/pitch/yaw differences (estimate - ground truth, each wrapped to
  /// [-180, 180) deg): the signed bias, e.g. a POS's heading error that a LiDAR-to-POS
  /// calibration inherits.
  Eigen::Vector3d rot_mean_rpy_deg = Eigen::Vector3d::Zero();
  double rot_max_deg = 0.0;

  std::vector<PoseError> errors;  ///< One per matched pose, in time order.
};

/// Summary statistics of per-pose errors (all of `errors`), as in AteResult. Fails on empty input.
StatusOr<AteResult> SummarizeErrors(std::vector<PoseError> errors);

/// Per-pose errors of matched poses after applying `T_gt_est` to the estimate.
std::vector<PoseError> ComputePoseErrors(const MatchedPoses& matched,
                                         const SimilarityTransform& T_gt_est);

/// ATE and rotation RMSE of `estimate` against `ground_truth` (stamps matched by interpolation).
StatusOr<AteResult> ComputeAte(const Trajectory& estimate, const Trajectory& ground_truth,
                               const AteOptions& options = AteOptions());

/// The same on already matched poses.
StatusOr<AteResult> ComputeAte(const MatchedPoses& matched, Alignment alignment);

/// Consistency of a trajectory's own covariances against the ground truth: per matched pose the
/// normalised estimation error squared of the position (3 dof; error in world, covariance's
/// translation block taken from body to world) and of the attitude (3 dof, right perturbation),
/// and the share inside the two-sided 95 % chi-square interval [0.216, 9.348]. A consistent
/// estimator has a mean near 3 and about 95 % inside; a mean far above 3 is overconfident.
struct NeesResult {
  size_t num_epochs = 0;  ///< Matched poses with a usable (positive definite) covariance.
  double position_mean = 0.0;
  double position_fraction_inside_95 = 0.0;
  double attitude_mean = 0.0;
  double attitude_fraction_inside_95 = 0.0;
};

/// Fails where no pose of `estimate` carries a usable covariance or none can be matched. Only
/// meaningful for absolute covariances (a POS); level 1's are relative to their submap.
StatusOr<NeesResult> ComputeNees(const Trajectory& estimate, const Trajectory& ground_truth);

/// A relative-pose measurement (T_a_b with its covariance, rotation first, as level 2's factors)
/// against the truth: error = se3::Log(T_a_b_true^-1 * T_a_b), rotation first, and its chi2
/// (6 dof) against the covariance. chi2 is NaN where the covariance is not positive definite.
struct RelativePoseError {
  Eigen::Matrix<double, 6, 1> error = Eigen::Matrix<double, 6, 1>::Zero();
  double chi2 = 0.0;
};
RelativePoseError RelativePoseErrorAgainstTruth(const Eigen::Isometry3d& T_a_b,
                                                const Eigen::Matrix<double, 6, 6>& covariance,
                                                const Eigen::Isometry3d& T_world_a_true,
                                                const Eigen::Isometry3d& T_world_b_true);

/// Wraps an angle to (-pi, pi].
double WrapAngle(double angle_rad);

}  // namespace slam_mms::eval
