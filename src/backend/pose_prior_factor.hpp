#pragma once
// PosePriorFactor: a full 6-DoF prior on one pose block, used to anchor a graph (the first state of
// the sliding window, the first submap) or to carry known information about a pose:
//
//   r = S * [ Log(R~^T R) ;  R~^T (p - p~) ]        (rotation first, right perturbation)
//
// with S^T S = Sigma^-1 of the 6x6 prior covariance (library convention: T = T~ * Exp(xi)).
// Parameter block: one 7-double pose block (backend/pose_block.hpp). Analytic Jacobian with
// respect to the ambient 7-vector.
//
// Thread safety: Evaluate is const and may run concurrently.

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms {

class PosePriorFactor final : public ceres::SizedCostFunction<6, 7> {
 public:
  /// Validates the prior pose and covariance (finite, symmetric, positive definite).
  static StatusOr<std::unique_ptr<PosePriorFactor>> Create(const Eigen::Isometry3d& T_world_prior,
                                                           const Matrix6d& covariance);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  const Eigen::Isometry3d& prior() const { return T_prior_; }

 private:
  PosePriorFactor(const Eigen::Isometry3d& T_prior, const Matrix6d& sqrt_information);

  Eigen::Isometry3d T_prior_;
  Eigen::Matrix3d R_prior_T_;
  Matrix6d sqrt_information_;
};

}  // namespace slam_mms
