#pragma once
// The point-to-plane residual of eq 15 (paper) and its Jacobian for the right perturbation
// T = T_hat * Exp(delta), delta = [omega; v] (rotation first).
//
//   r(T) = n_t . (T p_s - q_t)
//   T Exp(delta) p ~= T p + R (omega x p) + R v
//   => dr/domega = (p_s x R^T n_t)^T,  dr/dv = (R^T n_t)^T.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "slam_mms/core/lie.hpp"

namespace slam_mms::registration_internal {

/// Residual [m] of source point p_s (source frame) against the plane (q_t, n_t) of the target
/// frame; writes the 1x6 Jacobian (as a column) when J != nullptr. Scalar: float (ProjectiveIcp's
/// hot loop) or double (PointIcp).
template <typename Scalar>
inline Scalar PointToPlaneResidual(const Eigen::Matrix<Scalar, 3, 3>& R_target_source,
                                   const Eigen::Matrix<Scalar, 3, 1>& t_target_source,
                                   const Eigen::Matrix<Scalar, 3, 1>& p_source,
                                   const Eigen::Matrix<Scalar, 3, 1>& q_target,
                                   const Eigen::Matrix<Scalar, 3, 1>& n_target,
                                   Eigen::Matrix<Scalar, 6, 1>* J) {
  const Eigen::Matrix<Scalar, 3, 1> p_target = R_target_source * p_source + t_target_source;
  if (J != nullptr) {
    const Eigen::Matrix<Scalar, 3, 1> n_source = R_target_source.transpose() * n_target;
    J->template head<3>() = p_source.cross(n_source);
    J->template tail<3>() = n_source;
  }
  return n_target.dot(p_target - q_target);
}

/// Huber weight w(r) = 1 for |r| <= k, k / |r| beyond (k <= 0: no robust loss).
inline double HuberWeight(double r, double k) {
  if (k <= 0.0) return 1.0;
  const double a = std::abs(r);
  return a <= k ? 1.0 : k / a;
}

}  // namespace slam_mms::registration_internal
