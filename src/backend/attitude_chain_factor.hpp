#pragma once
// AttitudeChainFactor: two attitude measurements of one source (a POS) on submaps a and b whose
// errors are correlated in time. The measurement error in world axes,
//
//   eps_k = Log(R_k R~_k^T)        (R~_k measured, R_k the submap's estimate),
//
// is taken as a first-order Gauss-Markov process with marginal covariance Sigma_k (world axes) and
// correlation rho = exp(-dt / tau) between the two measurements: u_k = Sigma_k^-1/2 eps_k is
// N(0, I) and u_b = rho u_a + sqrt(1 - rho^2) w, w ~ N(0, I). Its residual is the whitened
// innovation
//
//   r = (Sigma_b^-1/2 eps_b - rho Sigma_a^-1/2 eps_a) / sqrt(1 - rho^2).
//
// Chained submap after submap, behind one ordinary prior N(0, Sigma_0) on the first, these factors
// are the exact joint density of the measurements' errors (the AR(1) precision is tridiagonal):
// rho = 0 gives independent priors, rho -> 1 one prior on the first submap plus the measured
// relative attitude between consecutive submaps. 1 - rho^2 is floored at kMinInnovationShare.
//
// The covariances are given as the library states attitude covariances (right perturbation, in
// the submap's own axes) and turned into world axes with the measured attitude.
// Parameter blocks: two 7-double pose blocks (backend/pose_block.hpp), a then b; automatic
// differentiation with respect to the ambient 7-vectors.
//
// Thread safety: Evaluate is const and may run concurrently.

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <memory>

#include "slam_mms/core/status.hpp"

namespace slam_mms {

struct AttitudeChainFactor {
  /// 1 - rho^2 never below this (the innovation's sigma at least 1 % of the marginal sigma).
  static constexpr double kMinInnovationShare = 1e-4;

  /// Validates the rotations (orthonormal), covariances (symmetric positive definite) and
  /// rho (in [0, 1]); the cost function takes the blocks of a then b.
  static StatusOr<std::unique_ptr<ceres::CostFunction>> Create(const Eigen::Matrix3d& R_world_a,
                                                               const Eigen::Matrix3d& cov_a,
                                                               const Eigen::Matrix3d& R_world_b,
                                                               const Eigen::Matrix3d& cov_b,
                                                               double rho);
};

}  // namespace slam_mms
