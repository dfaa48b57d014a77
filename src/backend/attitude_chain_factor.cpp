#include "backend/attitude_chain_factor.hpp"

#include <ceres/autodiff_cost_function.h>
#include <ceres/rotation.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "backend/pose_block.hpp"

namespace slam_mms {
namespace {

/// Sigma^-1/2 (symmetric): the same whitening whichever way the axes are turned.
Eigen::Matrix3d InverseSqrt(const Eigen::Matrix3d& cov) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(0.5 * (cov + cov.transpose()));
  return es.eigenvectors() * es.eigenvalues().cwiseSqrt().cwiseInverse().asDiagonal() *
         es.eigenvectors().transpose();
}

bool IsRotation(const Eigen::Matrix3d& R) {
  return R.allFinite() && (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-6 &&
         R.determinant() > 0.0;
}

Status CheckCovariance(const Eigen::Matrix3d& c, const char* which) {
  if (!c.allFinite() || (c - c.transpose()).norm() > 1e-9 * std::max(1.0, c.norm())) {
    return InvalidArgumentError(std::string("AttitudeChainFactor: ") + which +
                                " is not a finite symmetric matrix");
  }
  if (Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c).eigenvalues().minCoeff() <= 0.0) {
    return InvalidArgumentError(std::string("AttitudeChainFactor: ") + which +
                                " is not positive definite");
  }
  return OkStatus();
}

struct Residual {
  Eigen::Quaterniond q_a_inv, q_b_inv;  // R~^T of each measurement
  Eigen::Matrix3d W_a, W_b;             // rho Sigma_a^-1/2 and Sigma_b^-1/2, over sqrt(1 - rho^2)

  template <typename T>
  static Eigen::Matrix<T, 3, 1> WorldError(const T* pose, const Eigen::Quaterniond& q_inv) {
    const Eigen::Quaternion<T> q(pose[6], pose[3], pose[4], pose[5]);
    const Eigen::Quaternion<T> e = q * q_inv.cast<T>();  // R R~^T
    const T wxyz[4] = {e.w(), e.x(), e.y(), e.z()};
    Eigen::Matrix<T, 3, 1> aa;
    ceres::QuaternionToAngleAxis(wxyz, aa.data());
    return aa;
  }

  template <typename T>
  bool operator()(const T* pose_a, const T* pose_b, T* residual) const {
    Eigen::Map<Eigen::Matrix<T, 3, 1>> r(residual);
    r = W_b.cast<T>() * WorldError(pose_b, q_b_inv) - W_a.cast<T>() * WorldError(pose_a, q_a_inv);
    return true;
  }
};

}  // namespace

StatusOr<std::unique_ptr<ceres::CostFunction>> AttitudeChainFactor::Create(
    const Eigen::Matrix3d& R_world_a, const Eigen::Matrix3d& cov_a,
    const Eigen::Matrix3d& R_world_b, const Eigen::Matrix3d& cov_b, double rho) {
  if (!IsRotation(R_world_a) || !IsRotation(R_world_b)) {
    return InvalidArgumentError("AttitudeChainFactor: a measured attitude is not a rotation");
  }
  SLAM_MMS_RETURN_IF_ERROR(CheckCovariance(cov_a, "covariance of a"));
  SLAM_MMS_RETURN_IF_ERROR(CheckCovariance(cov_b, "covariance of b"));
  if (!(rho >= 0.0 && rho <= 1.0)) {
    return InvalidArgumentError("AttitudeChainFactor: rho = " + std::to_string(rho) +
                                "; must be in [0, 1]");
  }
  auto r = std::make_unique<Residual>();
  r->q_a_inv = Eigen::Quaterniond(R_world_a).normalized().conjugate();
  r->q_b_inv = Eigen::Quaterniond(R_world_b).normalized().conjugate();
  const double scale = 1.0 / std::sqrt(std::max(1.0 - rho * rho, kMinInnovationShare));
  // World axes: Sigma_w = R~ Sigma R~^T.
  r->W_a = rho * scale * InverseSqrt(R_world_a * cov_a * R_world_a.transpose());
  r->W_b = scale * InverseSqrt(R_world_b * cov_b * R_world_b.transpose());
  return std::unique_ptr<ceres::CostFunction>(
      new ceres::AutoDiffCostFunction<Residual, 3, kPoseBlockSize, kPoseBlockSize>(r.release()));
}

}  // namespace slam_mms
