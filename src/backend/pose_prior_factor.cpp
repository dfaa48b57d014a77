#include "backend/pose_prior_factor.hpp"

#include "backend/backend_math.hpp"
#include "backend/pose_block.hpp"

namespace slam_mms {

using backend_internal::SqrtInformation;
using backend_internal::ValidateCovariance;
using backend_internal::ValidatePose;

StatusOr<std::unique_ptr<PosePriorFactor>> PosePriorFactor::Create(
    const Eigen::Isometry3d& T_world_prior, const Matrix6d& covariance) {
  SLAM_MMS_RETURN_IF_ERROR(ValidatePose(T_world_prior, "PosePriorFactor prior"));
  SLAM_MMS_RETURN_IF_ERROR(ValidateCovariance<6>(covariance, "PosePriorFactor"));
  return std::unique_ptr<PosePriorFactor>(
      new PosePriorFactor(T_world_prior, SqrtInformation<6>(covariance)));
}

PosePriorFactor::PosePriorFactor(const Eigen::Isometry3d& T_prior, const Matrix6d& sqrt_information)
    : T_prior_(T_prior),
      R_prior_T_(T_prior.linear().transpose()),
      sqrt_information_(sqrt_information) {}

bool PosePriorFactor::Evaluate(double const* const* parameters, double* residuals,
                               double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> p(parameters[0]);
  const Eigen::Quaterniond q_raw(Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3));
  const double n = q_raw.norm();
  if (!(n > 0.0)) return false;
  const Eigen::Quaterniond q = q_raw.normalized();
  Vector6d r;
  r.head<3>() = so3::Log(Eigen::Matrix3d(R_prior_T_ * q.toRotationMatrix()));
  r.tail<3>() = R_prior_T_ * (p - T_prior_.translation());
  Eigen::Map<Vector6d> residual_out(residuals);
  residual_out = sqrt_information_ * r;
  if (jacobians == nullptr || jacobians[0] == nullptr) return true;
  using Mat67 = Eigen::Matrix<double, 6, 7, Eigen::RowMajor>;
  Mat67 J = Mat67::Zero();
  J.block<3, 3>(3, 0) = R_prior_T_;
  J.block<3, 4>(0, 3) =
      so3::RightJacobianInverse(r.head<3>()) * QuaternionRightTangentToAmbient(q) / n;
  Eigen::Map<Mat67> jacobian_out(jacobians[0]);
  jacobian_out = sqrt_information_ * J;
  return true;
}

}  // namespace slam_mms
