#include "slam_mms/core/trajectory.hpp"

#include <algorithm>

#include "slam_mms/core/lie.hpp"

namespace slam_mms {

Status Trajectory::Add(const StampedPose& pose) {
  if (!poses_.empty() && !(poses_.back().stamp < pose.stamp)) {
    return InvalidArgumentError("trajectory pose " + std::to_string(poses_.size()) +
                                " at t = " + std::to_string(pose.stamp.nanoseconds()) +
                                " ns is not after the previous one at t = " +
                                std::to_string(poses_.back().stamp.nanoseconds()) + " ns");
  }
  if (!pose.T_world_body.matrix().allFinite()) {
    return InvalidArgumentError("trajectory pose " + std::to_string(poses_.size()) +
                                " has a non-finite T_world_body");
  }
  poses_.push_back(pose);
  return OkStatus();
}

Status Trajectory::Add(Timestamp stamp, const Eigen::Isometry3d& T_world_body) {
  StampedPose p;
  p.stamp = stamp;
  p.T_world_body = T_world_body;
  return Add(p);
}

StatusOr<Eigen::Isometry3d> Trajectory::Interpolate(Timestamp t, double tolerance_s) const {
  if (poses_.empty()) return FailedPreconditionError("Interpolate on an empty trajectory");
  if (t <= poses_.front().stamp) {
    if (poses_.front().stamp.SecondsSince(t) <= tolerance_s) return poses_.front().T_world_body;
    return OutOfRangeError("time " + std::to_string(t.nanoseconds()) +
                           " ns is before the trajectory start " +
                           std::to_string(poses_.front().stamp.nanoseconds()) + " ns");
  }
  if (t >= poses_.back().stamp) {
    if (t.SecondsSince(poses_.back().stamp) <= tolerance_s) return poses_.back().T_world_body;
    return OutOfRangeError("time " + std::to_string(t.nanoseconds()) +
                           " ns is after the trajectory end " +
                           std::to_string(poses_.back().stamp.nanoseconds()) + " ns");
  }
  const auto it = std::upper_bound(poses_.begin(), poses_.end(), t,
                                   [](Timestamp v, const StampedPose& p) { return v < p.stamp; });
  const StampedPose& b = *it;
  const StampedPose& a = *(it - 1);
  const double alpha = t.SecondsSince(a.stamp) / b.stamp.SecondsSince(a.stamp);
  return InterpolatePose(a.T_world_body, b.T_world_body, alpha);
}

double Trajectory::PathLength() const {
  double len = 0.0;
  for (size_t i = 1; i < poses_.size(); ++i) {
    len += (poses_[i].T_world_body.translation() - poses_[i - 1].T_world_body.translation()).norm();
  }
  return len;
}

}  // namespace slam_mms
