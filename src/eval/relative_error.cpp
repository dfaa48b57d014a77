#include "slam_mms/eval/relative_error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace slam_mms::eval {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

std::string FormatLength(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// evaluate_odometry.cpp: trajectoryDistances().
std::vector<double> TrajectoryDistances(const std::vector<Eigen::Isometry3d>& poses) {
  std::vector<double> dist(poses.size(), 0.0);
  for (size_t i = 1; i < poses.size(); ++i) {
    dist[i] = dist[i - 1] + (poses[i].translation() - poses[i - 1].translation()).norm();
  }
  return dist;
}

// evaluate_odometry.cpp: lastFrameFromSegmentLength(): first frame strictly beyond the length.
long LastFrameFromSegmentLength(const std::vector<double>& dist, size_t first_frame, double len) {
  for (size_t i = first_frame; i < dist.size(); ++i) {
    if (dist[i] > dist[first_frame] + len) return static_cast<long>(i);
  }
  return -1;
}

// evaluate_odometry.cpp: rotationError(): acos of the clamped 0.5 (trace - 1).
double RotationError(const Eigen::Isometry3d& pose_error) {
  const Eigen::Matrix3d& R = pose_error.linear();
  const double d = 0.5 * (R(0, 0) + R(1, 1) + R(2, 2) - 1.0);
  return std::acos(std::max(std::min(d, 1.0), -1.0));
}

}  // namespace

RelativeErrorOptions RelativeErrorOptions::Kitti() { return RelativeErrorOptions(); }

RelativeErrorOptions RelativeErrorOptions::ShortDrive() {
  RelativeErrorOptions o;
  o.segment_lengths_m = {10, 20, 30, 40, 50, 60, 70, 80};
  return o;
}

std::string RelativeErrorOptions::LengthsLabel() const {
  if (segment_lengths_m == Kitti().segment_lengths_m) return "kitti_100-800m";
  if (segment_lengths_m == ShortDrive().segment_lengths_m) return "short_10-80m";
  if (segment_lengths_m.empty()) return "custom_none";
  const auto [lo, hi] = std::minmax_element(segment_lengths_m.begin(), segment_lengths_m.end());
  return "custom_" + FormatLength(*lo) + "-" + FormatLength(*hi) + "m";
}

Status RelativeErrorOptions::Validate() const {
  if (segment_lengths_m.empty()) {
    return InvalidArgumentError(
        "RelativeErrorOptions::segment_lengths_m is empty; give at least one");
  }
  for (size_t i = 0; i < segment_lengths_m.size(); ++i) {
    if (!(segment_lengths_m[i] > 0.0) || !std::isfinite(segment_lengths_m[i])) {
      return InvalidArgumentError("RelativeErrorOptions::segment_lengths_m[" + std::to_string(i) +
                                  "] = " + FormatLength(segment_lengths_m[i]) +
                                  "; must be finite and > 0");
    }
  }
  if (step_frames <= 0) {
    return InvalidArgumentError(
        "RelativeErrorOptions::step_frames = " + std::to_string(step_frames) + "; must be > 0");
  }
  return OkStatus();
}

StatusOr<RelativeErrorResult> ComputeRelativeError(
    const std::vector<Eigen::Isometry3d>& T_world_gt,
    const std::vector<Eigen::Isometry3d>& T_world_est, const RelativeErrorOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (T_world_gt.size() != T_world_est.size()) {
    return InvalidArgumentError("ComputeRelativeError: " + std::to_string(T_world_gt.size()) +
                                " ground-truth poses but " + std::to_string(T_world_est.size()) +
                                " estimated poses; frame i must be frame i in both");
  }
  if (T_world_gt.size() < 2) {
    return InvalidArgumentError("ComputeRelativeError: " + std::to_string(T_world_gt.size()) +
                                " poses; at least 2 are needed");
  }
  RelativeErrorResult result;
  result.lengths_label = options.LengthsLabel();
  const std::vector<double> dist = TrajectoryDistances(T_world_gt);
  result.ground_truth_path_length_m = dist.back();

  result.per_length.resize(options.segment_lengths_m.size());
  for (size_t k = 0; k < options.segment_lengths_m.size(); ++k) {
    result.per_length[k].length_m = options.segment_lengths_m[k];
  }
  double sum_t = 0.0;
  double sum_r = 0.0;
  const size_t step = static_cast<size_t>(options.step_frames);
  for (size_t first = 0; first < T_world_gt.size(); first += step) {
    for (size_t k = 0; k < options.segment_lengths_m.size(); ++k) {
      const double len = options.segment_lengths_m[k];
      const long last = LastFrameFromSegmentLength(dist, first, len);
      if (last == -1) continue;
      const Eigen::Isometry3d delta_gt = T_world_gt[first].inverse() * T_world_gt[last];
      const Eigen::Isometry3d delta_est = T_world_est[first].inverse() * T_world_est[last];
      const Eigen::Isometry3d pose_error = delta_est.inverse() * delta_gt;
      const double r_err = RotationError(pose_error) / len;
      const double t_err = pose_error.translation().norm() / len;
      sum_t += t_err;
      sum_r += r_err;
      ++result.num_segments;
      SegmentLengthError& pl = result.per_length[k];
      pl.t_rel_pct += t_err;
      pl.r_rel_deg_per_100m += r_err;
      ++pl.num_segments;
    }
  }
  for (SegmentLengthError& pl : result.per_length) {
    if (pl.num_segments == 0) continue;
    pl.t_rel_pct *= 100.0 / static_cast<double>(pl.num_segments);
    pl.r_rel_deg_per_100m *= 100.0 * kRadToDeg / static_cast<double>(pl.num_segments);
  }
  if (result.num_segments == 0) {
    result.t_rel_pct = std::numeric_limits<double>::quiet_NaN();
    result.r_rel_deg_per_100m = std::numeric_limits<double>::quiet_NaN();
  } else {
    const double n = static_cast<double>(result.num_segments);
    result.t_rel_pct = 100.0 * sum_t / n;
    result.r_rel_deg_per_100m = 100.0 * kRadToDeg * sum_r / n;
  }
  return result;
}

StatusOr<RelativeErrorResult> ComputeRelativeError(const Trajectory& estimate,
                                                   const Trajectory& ground_truth,
                                                   const RelativeErrorOptions& options,
                                                   const MatchOptions& match_options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  SLAM_MMS_ASSIGN_OR_RETURN(MatchedPoses matched,
                            MatchByTimestamp(estimate, ground_truth, match_options));
  return ComputeRelativeError(matched.T_world_gt, matched.T_world_est, options);
}

StatusOr<RelativeErrorResult> CombineRelativeErrors(
    const std::vector<RelativeErrorResult>& results) {
  if (results.empty()) return InvalidArgumentError("CombineRelativeErrors: no results");
  RelativeErrorResult out;
  out.lengths_label = results.front().lengths_label;
  out.per_length = results.front().per_length;
  for (SegmentLengthError& pl : out.per_length) {
    pl.num_segments = 0;
    pl.t_rel_pct = 0.0;
    pl.r_rel_deg_per_100m = 0.0;
  }
  double sum_t = 0.0, sum_r = 0.0;
  for (size_t i = 0; i < results.size(); ++i) {
    const RelativeErrorResult& r = results[i];
    if (r.lengths_label != out.lengths_label || r.per_length.size() != out.per_length.size()) {
      return InvalidArgumentError("CombineRelativeErrors: result " + std::to_string(i) + " uses " +
                                  r.lengths_label + ", result 0 uses " + out.lengths_label);
    }
    out.ground_truth_path_length_m += r.ground_truth_path_length_m;
    if (r.num_segments == 0) continue;
    const double n = static_cast<double>(r.num_segments);
    sum_t += n * r.t_rel_pct;
    sum_r += n * r.r_rel_deg_per_100m;
    out.num_segments += r.num_segments;
    for (size_t k = 0; k < r.per_length.size(); ++k) {
      const SegmentLengthError& src = r.per_length[k];
      SegmentLengthError& dst = out.per_length[k];
      dst.t_rel_pct += static_cast<double>(src.num_segments) * src.t_rel_pct;
      dst.r_rel_deg_per_100m += static_cast<double>(src.num_segments) * src.r_rel_deg_per_100m;
      dst.num_segments += src.num_segments;
    }
  }
  for (SegmentLengthError& pl : out.per_length) {
    if (pl.num_segments == 0) continue;
    pl.t_rel_pct /= static_cast<double>(pl.num_segments);
    pl.r_rel_deg_per_100m /= static_cast<double>(pl.num_segments);
  }
  if (out.num_segments == 0) {
    out.t_rel_pct = std::numeric_limits<double>::quiet_NaN();
    out.r_rel_deg_per_100m = std::numeric_limits<double>::quiet_NaN();
  } else {
    out.t_rel_pct = sum_t / static_cast<double>(out.num_segments);
    out.r_rel_deg_per_100m = sum_r / static_cast<double>(out.num_segments);
  }
  return out;
}

}  // namespace slam_mms::eval
