#pragma once
// GNSS position factor F_GNSS (paper eq 24) on one pose block, with the antenna lever arm:
//
//   r_GNSS = sqrt_info * ( p_world_body + R_world_body * t_body_antenna - p~_world_antenna )
//
// The paper writes r = p_Nref - p~_GNSS (lever arm zero). The robust loss is the caller's choice
// (pass it to Problem::AddResidualBlock, e.g. ceres::HuberLoss / CauchyLoss scaled in sigmas, since
// the residual is whitened). Parameter block: pose[7] (pose_block.hpp); analytic Jacobian w.r.t.
// the ambient block.
//
// Thread safety: immutable after construction; Evaluate may run concurrently.

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <memory>
#include <utility>

#include "slam_mms/core/status.hpp"

namespace slam_mms {

class GnssPositionFactor final : public ceres::SizedCostFunction<3, 7> {
 public:
  /// Validates (finite values, symmetric positive definite covariance) before anything reaches
  /// Ceres. cov_world_antenna: 3x3 covariance of the measured antenna position in world [m^2].
  static StatusOr<std::unique_ptr<GnssPositionFactor>> Create(
      const Eigen::Vector3d& p_world_antenna, const Eigen::Matrix3d& cov_world_antenna,
      const Eigen::Vector3d& t_body_antenna);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  const Eigen::Matrix3d& sqrt_information() const { return sqrt_info_; }

 private:
  GnssPositionFactor(const Eigen::Vector3d& p_world_antenna, const Eigen::Matrix3d& sqrt_info,
                     const Eigen::Vector3d& t_body_antenna);

  Eigen::Vector3d p_world_antenna_;
  Eigen::Matrix3d sqrt_info_;
  Eigen::Vector3d t_body_antenna_;
};

/// F_GNSS with a GNSS bias b (a constant world offset of the fixes' datum, shared by the fixes
/// of one bias key): r = sqrt_info * (p_world_body + R_world_body * t_body_antenna + b - p~).
/// Parameter blocks: pose[7], bias[3].
class BiasedGnssPositionFactor final : public ceres::SizedCostFunction<3, 7, 3> {
 public:
  explicit BiasedGnssPositionFactor(std::unique_ptr<GnssPositionFactor> unbiased)
      : unbiased_(std::move(unbiased)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  std::unique_ptr<GnssPositionFactor> unbiased_;
};

/// A zero-mean prior on a 3-vector: r = sqrt_info * b. Parameter block: b[3].
class ZeroMeanPrior3Factor final : public ceres::SizedCostFunction<3, 3> {
 public:
  explicit ZeroMeanPrior3Factor(const Eigen::Matrix3d& sqrt_info) : sqrt_info_(sqrt_info) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Matrix3d sqrt_info_;
};

/// A Gauss-Markov step between two GNSS biases: r = sqrt_info * (b - transition * b_from), the
/// bias b given the earlier one (b = phi b_from + w, w ~ N(0, Q), sqrt_info^T sqrt_info = Q^-1).
/// Parameter blocks: b_from[3], b[3].
class GnssBiasLinkFactor final : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  GnssBiasLinkFactor(double transition, const Eigen::Matrix3d& sqrt_info)
      : transition_(transition), sqrt_info_(sqrt_info) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  double transition_;
  Eigen::Matrix3d sqrt_info_;
};

}  // namespace slam_mms
