#include "backend/gnss_position_factor.hpp"

#include <Eigen/Cholesky>

#include "backend/pose_block.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {

StatusOr<std::unique_ptr<GnssPositionFactor>> GnssPositionFactor::Create(
    const Eigen::Vector3d& p_world_antenna, const Eigen::Matrix3d& cov_world_antenna,
    const Eigen::Vector3d& t_body_antenna) {
  if (!p_world_antenna.allFinite() || !t_body_antenna.allFinite() ||
      !cov_world_antenna.allFinite()) {
    return InvalidArgumentError("GnssPositionFactor: non-finite position, covariance or lever arm");
  }
  if (!cov_world_antenna.isApprox(cov_world_antenna.transpose(), 1e-9)) {
    return InvalidArgumentError("GnssPositionFactor: covariance is not symmetric");
  }
  Eigen::LLT<Eigen::Matrix3d> llt(cov_world_antenna);
  if (llt.info() != Eigen::Success ||
      (llt.matrixL().toDenseMatrix().diagonal().array() <= 0).any()) {
    return InvalidArgumentError("GnssPositionFactor: covariance is not positive definite");
  }
  // cov = L L^T -> info = L^-T L^-1 -> sqrt_info = L^-1.
  const Eigen::Matrix3d sqrt_info = llt.matrixL().solve(Eigen::Matrix3d::Identity());
  return std::unique_ptr<GnssPositionFactor>(
      new GnssPositionFactor(p_world_antenna, sqrt_info, t_body_antenna));
}

GnssPositionFactor::GnssPositionFactor(const Eigen::Vector3d& p_world_antenna,
                                       const Eigen::Matrix3d& sqrt_info,
                                       const Eigen::Vector3d& t_body_antenna)
    : p_world_antenna_(p_world_antenna), sqrt_info_(sqrt_info), t_body_antenna_(t_body_antenna) {}

bool GnssPositionFactor::Evaluate(double const* const* parameters, double* residuals,
                                  double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> p(parameters[0]);
  const Eigen::Quaterniond q = Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized();
  const Eigen::Matrix3d R = q.toRotationMatrix();
  Eigen::Map<Eigen::Vector3d> res(residuals);
  res = sqrt_info_ * (p + R * t_body_antenna_ - p_world_antenna_);
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 7, Eigen::RowMajor>> J(jacobians[0]);
    J.leftCols<3>() = sqrt_info_;
    // R Exp(dtheta) t ~= R t - R [t]x dtheta.
    J.rightCols<4>() = -sqrt_info_ * R * so3::Hat(t_body_antenna_) *
                       QuaternionRightTangentToAmbient(q) /
                       Eigen::Map<const Eigen::Vector4d>(parameters[0] + 3).norm();
  }
  return true;
}

bool BiasedGnssPositionFactor::Evaluate(double const* const* parameters, double* residuals,
                                        double** jacobians) const {
  double* pose_jacobian[1] = {jacobians != nullptr ? jacobians[0] : nullptr};
  if (!unbiased_->Evaluate(parameters, residuals, jacobians != nullptr ? pose_jacobian : nullptr)) {
    return false;
  }
  const Eigen::Map<const Eigen::Vector3d> b(parameters[1]);
  Eigen::Map<Eigen::Vector3d> res(residuals);
  res += unbiased_->sqrt_information() * b;
  if (jacobians != nullptr && jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(jacobians[1]);
    J = unbiased_->sqrt_information();
  }
  return true;
}

bool ZeroMeanPrior3Factor::Evaluate(double const* const* parameters, double* residuals,
                                    double** jacobians) const {
  Eigen::Map<Eigen::Vector3d> res(residuals);
  res = sqrt_info_ * Eigen::Map<const Eigen::Vector3d>(parameters[0]);
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(jacobians[0]);
    J = sqrt_info_;
  }
  return true;
}

bool GnssBiasLinkFactor::Evaluate(double const* const* parameters, double* residuals,
                                  double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> b_from(parameters[0]), b(parameters[1]);
  Eigen::Map<Eigen::Vector3d> res(residuals);
  res = sqrt_info_ * (b - transition_ * b_from);
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(jacobians[0]);
    J = -transition_ * sqrt_info_;
  }
  if (jacobians != nullptr && jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(jacobians[1]);
    J = sqrt_info_;
  }
  return true;
}

}  // namespace slam_mms
