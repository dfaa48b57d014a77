#include "slam_mms/eval/trajectory_error.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/option_error.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms::eval {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

}  // namespace

Status MatchOptions::Validate() const {
  if (!(max_ground_truth_gap_s > 0.0)) {
    return internal::OptionError("MatchOptions", "max_ground_truth_gap_s", max_ground_truth_gap_s,
                                 "must be > 0");
  }
  if (!(end_tolerance_s >= 0.0)) {
    return internal::OptionError("MatchOptions", "end_tolerance_s", end_tolerance_s,
                                 "must be >= 0");
  }
  return OkStatus();
}

Status AteOptions::Validate() const { return match.Validate(); }

const char* AlignmentName(Alignment alignment) {
  switch (alignment) {
    case Alignment::kNone: return "none";
    case Alignment::kSe3: return "se3";
    case Alignment::kSim3: return "sim3";
  }
  return "unknown";
}

double WrapAngle(double angle_rad) {
  double a = std::remainder(angle_rad, 2.0 * M_PI);  // [-pi, pi]
  if (a <= -M_PI) a += 2.0 * M_PI;
  return a;
}

StatusOr<MatchedPoses> MatchByTimestamp(const Trajectory& estimate, const Trajectory& ground_truth,
                                        const MatchOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (estimate.empty()) return InvalidArgumentError("MatchByTimestamp: the estimate is empty");
  if (ground_truth.empty()) {
    return InvalidArgumentError("MatchByTimestamp: the ground truth is empty");
  }
  const std::vector<StampedPose>& gt = ground_truth.poses();
  MatchedPoses out;
  out.stamps.reserve(estimate.size());
  out.T_world_est.reserve(estimate.size());
  out.T_world_gt.reserve(estimate.size());
  for (const StampedPose& est : estimate.poses()) {
    const Timestamp t = est.stamp;
    // Bracketing ground-truth samples: the gap between them bounds interpolation.
    const auto it = std::lower_bound(gt.begin(), gt.end(), t,
                                     [](const StampedPose& p, Timestamp v) { return p.stamp < v; });
    if (it != gt.end() && it->stamp != t && it != gt.begin()) {
      const double gap_s = it->stamp.SecondsSince((it - 1)->stamp);
      if (gap_s > options.max_ground_truth_gap_s) {
        ++out.num_unmatched;
        continue;
      }
    }
    StatusOr<Eigen::Isometry3d> T_world_gt = ground_truth.Interpolate(t, options.end_tolerance_s);
    if (!T_world_gt.ok()) {
      ++out.num_unmatched;
      continue;
    }
    out.stamps.push_back(t);
    out.T_world_est.push_back(est.T_world_body);
    out.T_world_gt.push_back(*T_world_gt);
  }
  if (out.size() == 0) {
    return InvalidArgumentError(
        "MatchByTimestamp: no estimated pose lies inside the ground truth's time span (estimate " +
        std::to_string(estimate.start().seconds()) + ".." +
        std::to_string(estimate.end().seconds()) + " s, ground truth " +
        std::to_string(ground_truth.start().seconds()) + ".." +
        std::to_string(ground_truth.end().seconds()) + " s)");
  }
  return out;
}

std::vector<PoseError> ComputePoseErrors(const MatchedPoses& matched,
                                         const SimilarityTransform& T_gt_est) {
  std::vector<PoseError> errors;
  errors.reserve(matched.size());
  for (size_t i = 0; i < matched.size(); ++i) {
    const Eigen::Isometry3d& T_gt = matched.T_world_gt[i];
    const Eigen::Isometry3d& T_est = matched.T_world_est[i];
    PoseError e;
    e.stamp = matched.stamps[i];
    e.p_est_world = T_gt_est * Eigen::Vector3d(T_est.translation());
    e.p_gt_world = T_gt.translation();
    e.position_error_world = e.p_est_world - e.p_gt_world;
    e.position_error_m = e.position_error_world.norm();
    const Eigen::Matrix3d R_est = T_gt_est.R * T_est.linear();
    const Eigen::Matrix3d R_gt = T_gt.linear();
    const Eigen::Vector3d rpy_est = RollPitchYaw(R_est);
    const Eigen::Vector3d rpy_gt = RollPitchYaw(R_gt);
    for (int k = 0; k < 3; ++k) e.rpy_error_rad(k) = WrapAngle(rpy_est(k) - rpy_gt(k));
    e.rotation_error_rad = RotationAngle(R_gt.transpose() * R_est);
    errors.push_back(e);
  }
  return errors;
}

StatusOr<AteResult> SummarizeErrors(std::vector<PoseError> errors) {
  if (errors.empty()) return InvalidArgumentError("SummarizeErrors: no pose errors");
  AteResult r;
  const double n = static_cast<double>(errors.size());
  Eigen::Vector3d sq_xyz = Eigen::Vector3d::Zero();
  Eigen::Vector3d sq_rpy = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_rpy = Eigen::Vector3d::Zero();
  double sum = 0.0;
  double sq_rot = 0.0;
  std::vector<double> norms;
  norms.reserve(errors.size());
  for (const PoseError& e : errors) {
    sq_xyz += e.position_error_world.cwiseAbs2();
    sq_rpy += e.rpy_error_rad.cwiseAbs2();
    sum_rpy += e.rpy_error_rad;
    sq_rot += e.rotation_error_rad * e.rotation_error_rad;
    sum += e.position_error_m;
    r.ate_max_m = std::max(r.ate_max_m, e.position_error_m);
    r.rot_max_deg = std::max(r.rot_max_deg, e.rotation_error_rad * kRadToDeg);
    norms.push_back(e.position_error_m);
  }
  r.ate_rmse_xyz_m = (sq_xyz / n).cwiseSqrt();
  r.ate_rmse_m = std::sqrt(sq_xyz.sum() / n);
  r.ate_mean_m = sum / n;
  std::sort(norms.begin(), norms.end());
  const size_t m = norms.size() / 2;
  r.ate_median_m = norms.size() % 2 == 1 ? norms[m] : 0.5 * (norms[m - 1] + norms[m]);
  r.rot_rmse_deg = std::sqrt(sq_rot / n) * kRadToDeg;
  r.rot_rmse_rpy_deg = (sq_rpy / n).cwiseSqrt() * kRadToDeg;
  r.rot_mean_rpy_deg = sum_rpy / n * kRadToDeg;
  r.num_matched = errors.size();
  r.errors = std::move(errors);
  return r;
}

StatusOr<AteResult> ComputeAte(const MatchedPoses& matched, Alignment alignment) {
  if (matched.size() == 0) return InvalidArgumentError("ComputeAte: no matched poses");
  SimilarityTransform T_gt_est;
  if (alignment != Alignment::kNone) {
    std::vector<Eigen::Vector3d> src, dst;
    src.reserve(matched.size());
    dst.reserve(matched.size());
    for (size_t i = 0; i < matched.size(); ++i) {
      src.push_back(matched.T_world_est[i].translation());
      dst.push_back(matched.T_world_gt[i].translation());
    }
    StatusOr<SimilarityTransform> s = UmeyamaAlignment(src, dst, alignment == Alignment::kSim3);
    if (!s.ok())
      return s.status().WithContext("ComputeAte with " + std::string(AlignmentName(alignment)) +
                                    " alignment");
    T_gt_est = *s;
  }
  SLAM_MMS_ASSIGN_OR_RETURN(AteResult r, SummarizeErrors(ComputePoseErrors(matched, T_gt_est)));
  r.alignment = alignment;
  r.T_gt_est = T_gt_est;
  r.num_unmatched = matched.num_unmatched;
  return r;
}

StatusOr<AteResult> ComputeAte(const Trajectory& estimate, const Trajectory& ground_truth,
                               const AteOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  SLAM_MMS_ASSIGN_OR_RETURN(MatchedPoses matched,
                            MatchByTimestamp(estimate, ground_truth, options.match));
  return ComputeAte(matched, options.alignment);
}

StatusOr<NeesResult> ComputeNees(const Trajectory& estimate, const Trajectory& ground_truth) {
  SLAM_MMS_ASSIGN_OR_RETURN(MatchedPoses matched, MatchByTimestamp(estimate, ground_truth));
  // The matched stamps are a subsequence of the estimate's: walk both in order.
  constexpr double kLo = 0.2158, kHi = 9.348;  // chi-square, 3 dof, 2.5 % and 97.5 %
  NeesResult r;
  size_t in_p = 0, in_r = 0;
  size_t k = 0;
  const auto& poses = estimate.poses();
  for (size_t i = 0; i < matched.size(); ++i) {
    while (k < poses.size() && poses[k].stamp < matched.stamps[i]) ++k;
    if (k >= poses.size() || !poses[k].cov_T_world_body) continue;
    const Eigen::Matrix<double, 6, 6>& C = *poses[k].cov_T_world_body;
    const Eigen::Matrix3d R = matched.T_world_est[i].linear();
    const Eigen::Matrix3d P_pos = R * C.bottomRightCorner<3, 3>() * R.transpose();
    const Eigen::Matrix3d P_rot = C.topLeftCorner<3, 3>();
    const Eigen::LLT<Eigen::Matrix3d> llt_p(P_pos), llt_r(P_rot);
    if (llt_p.info() != Eigen::Success || llt_r.info() != Eigen::Success || !C.allFinite()) {
      continue;
    }
    const Eigen::Vector3d dp =
        matched.T_world_gt[i].translation() - matched.T_world_est[i].translation();
    const Eigen::Vector3d dr = so3::Log(R.transpose() * matched.T_world_gt[i].linear());
    const double np = dp.dot(llt_p.solve(dp)), nr = dr.dot(llt_r.solve(dr));
    if (!std::isfinite(np) || !std::isfinite(nr)) continue;
    ++r.num_epochs;
    r.position_mean += np;
    r.attitude_mean += nr;
    in_p += (np >= kLo && np <= kHi) ? 1 : 0;
    in_r += (nr >= kLo && nr <= kHi) ? 1 : 0;
  }
  if (r.num_epochs == 0) {
    return InvalidArgumentError(
        "ComputeNees: no matched pose of the estimate has a usable covariance");
  }
  const double n = static_cast<double>(r.num_epochs);
  r.position_mean /= n;
  r.attitude_mean /= n;
  r.position_fraction_inside_95 = static_cast<double>(in_p) / n;
  r.attitude_fraction_inside_95 = static_cast<double>(in_r) / n;
  return r;
}

RelativePoseError RelativePoseErrorAgainstTruth(const Eigen::Isometry3d& T_a_b,
                                                const Matrix6d& covariance,
                                                const Eigen::Isometry3d& T_world_a_true,
                                                const Eigen::Isometry3d& T_world_b_true) {
  RelativePoseError out;
  const Eigen::Isometry3d T_a_b_true = T_world_a_true.inverse() * T_world_b_true;
  out.error = se3::Log(T_a_b_true.inverse() * T_a_b);
  const Eigen::LLT<Matrix6d> llt(covariance);
  out.chi2 = llt.info() == Eigen::Success ? out.error.dot(llt.solve(out.error))
                                          : std::numeric_limits<double>::quiet_NaN();
  return out;
}

}  // namespace slam_mms::eval
