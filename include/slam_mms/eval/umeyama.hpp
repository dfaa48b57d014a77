#pragma once
// Umeyama (1991) least-squares alignment of two corresponding point sets: the similarity
// dst ~ s R src + t minimising sum |dst_i - (s R src_i + t)|^2, with or without the scale.
//
// Thread safety: free functions on value types; safe to call concurrently.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "slam_mms/core/status.hpp"

namespace slam_mms::eval {

/// p_a = scale * R_a_b * p_b + t_a_b.
struct SimilarityTransform {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double scale = 1.0;

  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return scale * (R * p) + t; }
  /// The rigid part (R, t); exact only where scale == 1.
  Eigen::Isometry3d Rigid() const;
};

/// The transform T_dst_src with dst_i ~ T_dst_src * src_i. `with_scale` false fixes scale = 1
/// (SE(3)). Fails on size mismatch, fewer than 3 pairs, non-finite input, or a degenerate
/// configuration (all points collinear or coincident: the rotation is not determined).
StatusOr<SimilarityTransform> UmeyamaAlignment(const std::vector<Eigen::Vector3d>& src,
                                               const std::vector<Eigen::Vector3d>& dst,
                                               bool with_scale);

}  // namespace slam_mms::eval
