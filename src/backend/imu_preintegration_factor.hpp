#pragma once
// IMU preintegration factor F_Pre (paper eq 14) between two states i, j, extended with the bias
// random walk so that a sliding window estimates the biases (the paper keeps them fixed):
//
//   r_R  = Log( (dR~ Exp(J_R^g dbg))^T R_i^T R_j )
//   r_v  = R_i^T (v_j - v_i - g dt) - (dv~ + J_v^a dba + J_v^g dbg)
//   r_p  = R_i^T (p_j - p_i - v_i dt - 1/2 g dt^2) - (dp~ + J_p^a dba + J_p^g dbg)
//   r_ba = ba_j - ba_i,   r_bg = bg_j - bg_i                (random walk, variance q_b^2 * dt)
//
// with db = b_i - b_bar (the preintegration's bias linearisation point). The 15 residuals are
// whitened by the square-root information of blockdiag(preintegration covariance, bias random
// walk). Parameter blocks (pose_block.hpp): pose_i[7], v_i[3], bias_i[6], pose_j[7], v_j[3],
// bias_j[6]. Jacobians are analytic, with respect to the ambient blocks. Add a prior on the first
// bias block (e.g. ceres::NormalPrior) so the biases are observable from the start of a window.
//
// Thread safety: immutable after construction; Evaluate may run concurrently.

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <memory>

#include "slam_mms/core/status.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"

namespace slam_mms {

using Matrix15d = Eigen::Matrix<double, 15, 15>;

class ImuPreintegrationFactor final : public ceres::SizedCostFunction<15, 7, 3, 6, 7, 3, 6> {
 public:
  /// Validates (at least one sample, positive definite covariance, finite gravity) before anything
  /// reaches Ceres. g_world: gravity vector in world, e.g. (0, 0, -9.80665).
  static StatusOr<std::unique_ptr<ImuPreintegrationFactor>> Create(
      const ImuPreintegration& preintegration, const Eigen::Vector3d& g_world);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  /// Unwhitened residual (for tests and consistency checks).
  Eigen::Matrix<double, 15, 1> UnwhitenedResidual(double const* const* parameters) const;

  const Matrix15d& sqrt_information() const { return sqrt_info_; }
  const ImuPreintegration& preintegration() const { return pre_; }

 private:
  ImuPreintegrationFactor(const ImuPreintegration& preintegration, const Eigen::Vector3d& g_world,
                          const Matrix15d& sqrt_info);

  ImuPreintegration pre_;
  Eigen::Vector3d g_world_;
  Matrix15d sqrt_info_;
};

}  // namespace slam_mms
