#pragma once
// Small covariance helpers shared by the pipeline (private).

#include "slam_mms/core/lie.hpp"

namespace slam_mms::internal {

/// 6x6 pose covariance (rotation first) with isotropic 1-sigma rotation [rad] and translation [m].
inline Matrix6d DiagonalPoseCovariance(double sigma_rot_rad, double sigma_trans_m) {
  Vector6d d;
  d << Eigen::Vector3d::Constant(sigma_rot_rad * sigma_rot_rad),
      Eigen::Vector3d::Constant(sigma_trans_m * sigma_trans_m);
  return d.asDiagonal();
}

}  // namespace slam_mms::internal
