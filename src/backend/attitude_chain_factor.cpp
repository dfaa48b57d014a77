#include "backend/attitude_chain_factor.hpp"

#include <ceres/autodiff_cost_function.h>
#include <ceres/rotation.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <string>

#include "backend/backend_math.hpp"
#include "backend/pose_block.hpp"
#include "slam_mms/backend/submap_graph.hpp"

namespace slam_mms {

using backend_internal::ValidateCovariance;
using backend_internal::ValidatePose;

namespace {

struct Residual {
  Eigen::Quaterniond q_a_inv, q_b_inv;  // R~^T of each measurement
  Eigen::Matrix3d W_a, W_b;             // S A and S, S^T S = Q^-1

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
    const Eigen::Matrix3d& R_world_a, const Eigen::Matrix3d& R_world_b,
    const Eigen::Matrix3d& transition, const Eigen::Matrix3d& covariance) {
  for (const Eigen::Matrix3d* R : {&R_world_a, &R_world_b}) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = *R;
    SLAM_MMS_RETURN_IF_ERROR(
        backend_internal::ValidatePose(T, "AttitudeChainFactor: measured attitude"));
  }
  if (!transition.allFinite()) {
    return InvalidArgumentError("AttitudeChainFactor: the transition is not finite");
  }
  SLAM_MMS_RETURN_IF_ERROR(
      backend_internal::ValidateCovariance<3>(covariance, "AttitudeChainFactor covariance"));
  auto r = std::make_unique<Residual>();
  r->q_a_inv = Eigen::Quaterniond(R_world_a).normalized().conjugate();
  r->q_b_inv = Eigen::Quaterniond(R_world_b).normalized().conjugate();
  r->W_b = backend_internal::SqrtInformation<3>(covariance);
  r->W_a = r->W_b * transition;
  return std::unique_ptr<ceres::CostFunction>(
      new ceres::AutoDiffCostFunction<Residual, 3, kPoseBlockSize, kPoseBlockSize>(r.release()));
}

namespace {

/// Sigma^(power) of a symmetric positive definite matrix (power +-1/2), symmetric root.
Eigen::Matrix3d SymmetricPower(const Eigen::Matrix3d& cov, double power) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(0.5 * (cov + cov.transpose()));
  return es.eigenvectors() * es.eigenvalues().array().pow(power).matrix().asDiagonal() *
         es.eigenvectors().transpose();
}

Status ValidateAttitude(const Eigen::Matrix3d& R, const Eigen::Matrix3d& cov,
                        const std::string& what) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  SLAM_MMS_RETURN_IF_ERROR(ValidatePose(T, what));
  return ValidateCovariance<3>(cov, what);
}

}  // namespace

StatusOr<AttitudeChain> AttitudeChainFromCrossCovariance(const Eigen::Matrix3d& R_world_a,
                                                         const Eigen::Matrix3d& cov_a,
                                                         const Eigen::Matrix3d& R_world_b,
                                                         const Eigen::Matrix3d& cov_b,
                                                         const Eigen::Matrix3d& cross_ba) {
  const std::string what = "AttitudeChainFromCrossCovariance";
  SLAM_MMS_RETURN_IF_ERROR(ValidateAttitude(R_world_a, cov_a, what + " (a)"));
  SLAM_MMS_RETURN_IF_ERROR(ValidateAttitude(R_world_b, cov_b, what + " (b)"));
  if (!cross_ba.allFinite()) return InvalidArgumentError(what + ": cross-covariance not finite");
  // World axes: eps = R e.
  const Eigen::Matrix3d Saa = R_world_a * cov_a * R_world_a.transpose();
  const Eigen::Matrix3d Sbb = R_world_b * cov_b * R_world_b.transpose();
  const Eigen::Matrix3d Sba = R_world_b * cross_ba * R_world_a.transpose();
  Eigen::Matrix<double, 6, 6> joint;
  joint << Saa, Sba.transpose(), Sba, Sbb;
  joint = 0.5 * (joint + joint.transpose());
  if (Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(joint).eigenvalues().minCoeff() <=
      0.0) {
    return InvalidArgumentError(what +
                                ": the joint covariance of a and b is not positive definite");
  }
  AttitudeChain c;
  c.transition = Saa.ldlt().solve(Sba.transpose()).transpose();
  const Eigen::Matrix3d Q = Sbb - c.transition * Sba.transpose();
  c.covariance = 0.5 * (Q + Q.transpose()) + kAttitudeChainMinInnovationShare * Sbb;
  return c;
}

StatusOr<AttitudeChain> GaussMarkovAttitudeChain(const Eigen::Matrix3d& R_world_a,
                                                 const Eigen::Matrix3d& cov_a,
                                                 const Eigen::Matrix3d& R_world_b,
                                                 const Eigen::Matrix3d& cov_b, double rho) {
  const std::string what = "GaussMarkovAttitudeChain";
  SLAM_MMS_RETURN_IF_ERROR(ValidateAttitude(R_world_a, cov_a, what + " (a)"));
  SLAM_MMS_RETURN_IF_ERROR(ValidateAttitude(R_world_b, cov_b, what + " (b)"));
  if (!(rho >= 0.0 && rho <= 1.0)) {
    return InvalidArgumentError(what + ": rho = " + std::to_string(rho) + "; must be in [0, 1]");
  }
  const Eigen::Matrix3d Saa = R_world_a * cov_a * R_world_a.transpose();
  const Eigen::Matrix3d Sbb = R_world_b * cov_b * R_world_b.transpose();
  AttitudeChain c;
  c.transition = rho * SymmetricPower(Sbb, 0.5) * SymmetricPower(Saa, -0.5);
  c.covariance = std::max(1.0 - rho * rho, kAttitudeChainMinInnovationShare) * Sbb;
  c.covariance = 0.5 * (c.covariance + c.covariance.transpose());
  return c;
}

}  // namespace slam_mms
