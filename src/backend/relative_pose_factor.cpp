#include "backend/relative_pose_factor.hpp"

#include "backend/backend_math.hpp"
#include "backend/pose_block.hpp"

namespace slam_mms {

using backend_internal::SqrtInformation;
using backend_internal::ValidateCovariance;
using backend_internal::ValidatePose;

StatusOr<std::unique_ptr<RelativePoseFactor>> RelativePoseFactor::Create(
    const Eigen::Isometry3d& T_a_b_measured, const Matrix6d& covariance) {
  SLAM_MMS_RETURN_IF_ERROR(ValidatePose(T_a_b_measured, "RelativePoseFactor measurement"));
  SLAM_MMS_RETURN_IF_ERROR(ValidateCovariance<6>(covariance, "RelativePoseFactor"));
  return std::unique_ptr<RelativePoseFactor>(
      new RelativePoseFactor(T_a_b_measured, SqrtInformation<6>(covariance)));
}

RelativePoseFactor::RelativePoseFactor(const Eigen::Isometry3d& T_a_b,
                                       const Matrix6d& sqrt_information)
    : T_a_b_(T_a_b), dR_T_(T_a_b.linear().transpose()), sqrt_information_(sqrt_information) {}

Vector6d RelativePoseFactor::UnweightedResidual(const Eigen::Isometry3d& T_world_a,
                                                const Eigen::Isometry3d& T_world_b) const {
  Vector6d r;
  const Eigen::Matrix3d Ra_T = T_world_a.linear().transpose();
  r.head<3>() = so3::Log(Eigen::Matrix3d(dR_T_ * Ra_T * T_world_b.linear()));
  r.tail<3>() = Ra_T * (T_world_b.translation() - T_world_a.translation()) - T_a_b_.translation();
  return r;
}

bool RelativePoseFactor::Evaluate(double const* const* parameters, double* residuals,
                                  double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> p_a(parameters[0]);
  const Eigen::Map<const Eigen::Vector3d> p_b(parameters[1]);
  const Eigen::Quaterniond q_a_raw(Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3));
  const Eigen::Quaterniond q_b_raw(Eigen::Map<const Eigen::Quaterniond>(parameters[1] + 3));
  const double n_a = q_a_raw.norm();
  const double n_b = q_b_raw.norm();
  if (!(n_a > 0.0) || !(n_b > 0.0)) return false;
  const Eigen::Quaterniond q_a = q_a_raw.normalized();
  const Eigen::Quaterniond q_b = q_b_raw.normalized();
  const Eigen::Matrix3d R_a = q_a.toRotationMatrix();
  const Eigen::Matrix3d R_b = q_b.toRotationMatrix();
  const Eigen::Matrix3d Ra_T = R_a.transpose();

  // Eq. (12)/(16)/(21)/(23): r = [Log(dR~^T R_a^T R_b); R_a^T (p_b - p_a) - dp~].
  const Eigen::Vector3d d_world = p_b - p_a;
  const Eigen::Vector3d d_a = Ra_T * d_world;
  Vector6d r;
  r.head<3>() = so3::Log(Eigen::Matrix3d(dR_T_ * Ra_T * R_b));
  r.tail<3>() = d_a - T_a_b_.translation();
  Eigen::Map<Vector6d> residual_out(residuals);
  residual_out = sqrt_information_ * r;

  if (jacobians == nullptr) return true;
  // Right perturbations R_a Exp(da), R_b Exp(db); translations additive in the world frame.
  //   d r_rot / d db = Jr^-1(r_rot),  d r_rot / d da = -Jr^-1(r_rot) R_b^T R_a,
  //   d r_t / d da = Hat(R_a^T (p_b - p_a)),  d r_t / d p_a = -R_a^T,  d r_t / d p_b = R_a^T.
  const Eigen::Matrix3d Jr_inv = so3::RightJacobianInverse(r.head<3>());
  using Mat67 = Eigen::Matrix<double, 6, 7, Eigen::RowMajor>;
  if (jacobians[0] != nullptr) {
    Eigen::Matrix<double, 6, 3> J_theta;
    J_theta.topRows<3>() = -Jr_inv * R_b.transpose() * R_a;
    J_theta.bottomRows<3>() = so3::Hat(d_a);
    Mat67 J;
    J.leftCols<3>().topRows<3>().setZero();
    J.leftCols<3>().bottomRows<3>() = -Ra_T;
    J.rightCols<4>() = J_theta * QuaternionRightTangentToAmbient(q_a) / n_a;
    Eigen::Map<Mat67> jacobian_out(jacobians[0]);
    jacobian_out = sqrt_information_ * J;
  }
  if (jacobians[1] != nullptr) {
    Mat67 J;
    J.leftCols<3>().topRows<3>().setZero();
    J.leftCols<3>().bottomRows<3>() = Ra_T;
    J.rightCols<4>().topRows<3>() = Jr_inv * QuaternionRightTangentToAmbient(q_b) / n_b;
    J.rightCols<4>().bottomRows<3>().setZero();
    Eigen::Map<Mat67> jacobian_out(jacobians[1]);
    jacobian_out = sqrt_information_ * J;
  }
  return true;
}

}  // namespace slam_mms
