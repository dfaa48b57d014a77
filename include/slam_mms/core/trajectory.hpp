#pragma once
// Trajectory: time-ordered stamped poses T_world_body with optional 6x6 covariances, and pose
// interpolation at any time inside its span. Shared by io (TUM/KITTI/CSV files), eval (metrics) and
// the pipeline (outputs).
//
// Thread safety: value type; concurrent const access is safe.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms {

struct StampedPose {
  Timestamp stamp;
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  /// Rotation first [omega, v], right perturbation; absent where unknown.
  std::optional<Eigen::Matrix<double, 6, 6>> cov_T_world_body;
};

class Trajectory {
 public:
  Trajectory() = default;

  /// Appends a pose; stamps must be strictly increasing (returns kInvalidArgument otherwise, naming
  /// the index and both stamps).
  Status Add(const StampedPose& pose);
  Status Add(Timestamp stamp, const Eigen::Isometry3d& T_world_body);

  size_t size() const { return poses_.size(); }
  bool empty() const { return poses_.empty(); }
  const StampedPose& operator[](size_t i) const { return poses_[i]; }
  const std::vector<StampedPose>& poses() const { return poses_; }
  Timestamp start() const { return poses_.front().stamp; }
  Timestamp end() const { return poses_.back().stamp; }

  /// Pose at `t` by InterpolatePose between the neighbouring samples; kOutOfRange outside
  /// [start(), end()] beyond `tolerance_s`, inside which the end pose is returned.
  StatusOr<Eigen::Isometry3d> Interpolate(Timestamp t, double tolerance_s = 1e-6) const;

  /// Sum of distances between consecutive positions [m].
  double PathLength() const;

 private:
  std::vector<StampedPose> poses_;
};

}  // namespace slam_mms
