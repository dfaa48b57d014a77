#pragma once
// KITTI relative error, computed exactly as the KITTI odometry devkit's evaluate_odometry.cpp does
// (paper Fig. 7): path distances along the GROUND TRUTH; a segment starts every `step_frames`
// frames; for each start and each length L the segment ends at the first frame whose distance is
// STRICTLY beyond dist[first] + L (no segment where none is); the error pose is
// inv(delta_est) * delta_gt with delta = inv(T[first]) * T[last]; its translation norm / L and its
// rotation angle / L are one sample each; the results are plain means over all (start, length)
// pairs. Differences from the devkit: double instead of float arithmetic; lengths are configurable
// (the default is the devkit's 100..800 m; ShortDrive() gives 10..80 m for short drives, labelled
// so).
//
// Thread safety: free functions on value types; safe to call concurrently.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/eval/trajectory_error.hpp"

namespace slam_mms::eval {

struct RelativeErrorOptions {
  /// Segment lengths along the ground-truth path [m]; the devkit's 100, 200, ..., 800 by default.
  std::vector<double> segment_lengths_m = {100, 200, 300, 400, 500, 600, 700, 800};
  /// A segment starts every this many frames (the devkit: 10, one second of KITTI frames).
  int step_frames = 10;

  /// The devkit's lengths (the default).
  static RelativeErrorOptions Kitti();
  /// 10, 20, ..., 80 m for drives too short for the devkit's lengths.
  static RelativeErrorOptions ShortDrive();

  /// "kitti_100-800m" for the devkit's lengths, "short_10-80m" for ShortDrive(), else
  /// "custom_<a>-<b>m".
  std::string LengthsLabel() const;

  [[nodiscard]] Status Validate() const;
};

/// Statistics of the segments of one length.
struct SegmentLengthError {
  double length_m = 0.0;
  size_t num_segments = 0;
  double t_rel_pct = 0.0;           ///< Mean translation error / length * 100 (0 if no segment).
  double r_rel_deg_per_100m = 0.0;  ///< Mean rotation error / length, deg per 100 m.
};

struct RelativeErrorResult {
  std::string lengths_label;  ///< RelativeErrorOptions::LengthsLabel() of the options used.
  /// Number of (start, length) pairs evaluated; 0 when the drive is shorter than every length, in
  /// which case the means below are NaN (report them as null).
  size_t num_segments = 0;
  double t_rel_pct = 0.0;           ///< Plain mean over all pairs of t_err / L, in %.
  double r_rel_deg_per_100m = 0.0;  ///< Plain mean over all pairs of r_err / L, deg per 100 m.
  std::vector<SegmentLengthError> per_length;
  double ground_truth_path_length_m = 0.0;
};

/// The devkit metric on two equally long pose sequences (frame i of one is frame i of the other,
/// as in KITTI pose files). Fails on a size mismatch, fewer than 2 poses or bad options.
StatusOr<RelativeErrorResult> ComputeRelativeError(
    const std::vector<Eigen::Isometry3d>& T_world_gt,
    const std::vector<Eigen::Isometry3d>& T_world_est,
    const RelativeErrorOptions& options = RelativeErrorOptions());

/// The same on a timestamped estimate: frames are the estimated poses, each paired with the ground
/// truth interpolated at its stamp (see MatchByTimestamp).
StatusOr<RelativeErrorResult> ComputeRelativeError(
    const Trajectory& estimate, const Trajectory& ground_truth,
    const RelativeErrorOptions& options = RelativeErrorOptions(),
    const MatchOptions& match_options = MatchOptions());

/// The devkit's number over several sequences: the plain mean over all (start, length) pairs of
/// all of them (each result weighted by its num_segments). Fails on an empty list or results with
/// different lengths labels.
StatusOr<RelativeErrorResult> CombineRelativeErrors(
    const std::vector<RelativeErrorResult>& results);

}  // namespace slam_mms::eval
