#pragma once
// AttitudeChainFactor: two attitude measurements of one source (a POS) on submaps a and b whose
// errors are correlated. The measurement error in world axes,
//
//   eps_k = Log(R_k R~_k^T)        (R~_k measured, R_k the submap's estimate),
//
// of b given a's is eps_b = A eps_a + w, w ~ N(0, Q) (SubmapGraph's AttitudeChain: from the
// POS filter's cross-covariance, or a Gauss-Markov correlation). The residual is the whitened
// innovation
//
//   r = Q^-1/2 (eps_b - A eps_a).
//
// Chained submap after submap, behind one ordinary prior on the first submap, these factors are
// the joint density of the measurements' errors as a Markov chain (for a first-order Gauss-Markov
// error exact: its precision is tridiagonal).
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
  /// Validates the rotations (orthonormal), A (finite) and Q (symmetric positive definite); the
  /// cost function takes the blocks of a then b.
  static StatusOr<std::unique_ptr<ceres::CostFunction>> Create(const Eigen::Matrix3d& R_world_a,
                                                               const Eigen::Matrix3d& R_world_b,
                                                               const Eigen::Matrix3d& transition,
                                                               const Eigen::Matrix3d& covariance);
};

}  // namespace slam_mms
