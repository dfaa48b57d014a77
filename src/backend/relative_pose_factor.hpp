#pragma once
// RelativePoseFactor: the between factor of the hierarchical graph, one cost function for
//   F_Odom   (eq 12, GNSS/INS odometry from the submap reference to scan i),
//   F_Reg    (eq 16, scan-to-map registration; level 2: map-to-map registration),
//   F_Reckon (eq 21, serial scan-to-map chain between consecutive submaps),
//   F_Loop   (eqs 22-23, loop closure between submaps N and M).
// With poses a = (R_a, p_a) and b = (R_b, p_b) in one frame and the measurement T~_a_b = (dR~,
// dp~):
//
//   r = S * [ Log(dR~^T R_a^T R_b) ;  R_a^T (p_b - p_a) - dp~ ]        (rotation first)
//
// where S is the upper-triangular square-root information, S^T S = Sigma^-1, of the 6x6 covariance
// Sigma of the measurement in the library's convention (rotation first, right perturbation:
// T_a_b = T~_a_b * Exp(xi), xi ~ N(0, Sigma)).
//
// Parameter blocks: the 7-double pose blocks of backend/pose_block.hpp ([t, q(xyzw)],
// T_world_a and T_world_b), manifold PoseManifold. Jacobians are analytic, with respect to the
// ambient 7-vectors (Ceres chains them with the manifold).
//
// Thread safety: Evaluate is const and may run concurrently (Ceres does so).

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms {

class RelativePoseFactor final : public ceres::SizedCostFunction<6, 7, 7> {
 public:
  /// Validates the measurement (finite, orthonormal rotation) and the covariance (finite,
  /// symmetric, positive definite) before anything reaches Ceres.
  static StatusOr<std::unique_ptr<RelativePoseFactor>> Create(
      const Eigen::Isometry3d& T_a_b_measured, const Matrix6d& covariance);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  /// The unweighted residual [Log(dR~^T R_a^T R_b); R_a^T(p_b - p_a) - dp~] for two poses.
  Vector6d UnweightedResidual(const Eigen::Isometry3d& T_world_a,
                              const Eigen::Isometry3d& T_world_b) const;

  const Eigen::Isometry3d& measurement() const { return T_a_b_; }
  const Matrix6d& sqrt_information() const { return sqrt_information_; }

 private:
  RelativePoseFactor(const Eigen::Isometry3d& T_a_b, const Matrix6d& sqrt_information);

  Eigen::Isometry3d T_a_b_;
  Eigen::Matrix3d dR_T_;  // dR~^T
  Matrix6d sqrt_information_;
};

}  // namespace slam_mms
