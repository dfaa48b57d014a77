#include "backend/imu_preintegration_factor.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "backend/pose_block.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {

namespace {
using Matrix15x6 = Eigen::Matrix<double, 15, 6>;
using Matrix15x7R = Eigen::Matrix<double, 15, 7, Eigen::RowMajor>;
using Matrix15x3R = Eigen::Matrix<double, 15, 3, Eigen::RowMajor>;
using Matrix15x6R = Eigen::Matrix<double, 15, 6, Eigen::RowMajor>;

// Jacobian w.r.t. the local pose tangent [dp (world, additive), dtheta (right)] -> ambient 7-block.
// The residual reads the normalised quaternion, so the ambient Jacobian carries 1 / |q_ambient|.
void LocalPoseToAmbient(const Matrix15x6& J_local, const Eigen::Quaterniond& q, double q_norm,
                        double* out) {
  Eigen::Map<Matrix15x7R> J(out);
  J.leftCols<3>() = J_local.leftCols<3>();
  J.rightCols<4>() = J_local.rightCols<3>() * QuaternionRightTangentToAmbient(q) / q_norm;
}
}  // namespace

StatusOr<std::unique_ptr<ImuPreintegrationFactor>> ImuPreintegrationFactor::Create(
    const ImuPreintegration& preintegration, const Eigen::Vector3d& g_world) {
  SLAM_MMS_RETURN_IF_ERROR(preintegration.options().Validate());
  if (preintegration.num_samples() < 1 || !(preintegration.delta_t_s() > 0.0)) {
    return InvalidArgumentError("ImuPreintegrationFactor: the preintegration holds no samples");
  }
  if (!g_world.allFinite())
    return InvalidArgumentError("ImuPreintegrationFactor: gravity not finite");
  if (!preintegration.covariance().allFinite()) {
    return InvalidArgumentError("ImuPreintegrationFactor: preintegration covariance not finite");
  }
  Matrix15d cov = Matrix15d::Zero();
  cov.topLeftCorner<9, 9>() = preintegration.covariance();
  const double dt = preintegration.delta_t_s();
  const auto& o = preintegration.options();
  cov.block<3, 3>(9, 9).diagonal().setConstant(o.accel_bias_random_walk * o.accel_bias_random_walk *
                                               dt);
  cov.block<3, 3>(12, 12).diagonal().setConstant(o.gyro_bias_random_walk * o.gyro_bias_random_walk *
                                                 dt);
  // A single sample gives a rank-deficient (dv, dp) block: floor the eigenvalues relative to the
  // largest so the information stays finite (the floor is far below any physical noise level).
  Eigen::SelfAdjointEigenSolver<Matrix15d> es(0.5 * (cov + cov.transpose()));
  if (es.info() != Eigen::Success)
    return InternalError("ImuPreintegrationFactor: eigen solver failed");
  Eigen::Matrix<double, 15, 1> lambda = es.eigenvalues();
  const double floor = std::max(lambda.maxCoeff() * 1e-12, 1e-30);
  for (int k = 0; k < 15; ++k) lambda[k] = std::max(lambda[k], floor);
  // sqrt_info^T sqrt_info = cov^-1, with sqrt_info = diag(lambda^-1/2) V^T.
  const Matrix15d sqrt_info =
      lambda.cwiseSqrt().cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
  return std::unique_ptr<ImuPreintegrationFactor>(
      new ImuPreintegrationFactor(preintegration, g_world, sqrt_info));
}

ImuPreintegrationFactor::ImuPreintegrationFactor(const ImuPreintegration& preintegration,
                                                 const Eigen::Vector3d& g_world,
                                                 const Matrix15d& sqrt_info)
    : pre_(preintegration), g_world_(g_world), sqrt_info_(sqrt_info) {}

Eigen::Matrix<double, 15, 1> ImuPreintegrationFactor::UnwhitenedResidual(
    double const* const* parameters) const {
  Eigen::Matrix<double, 15, 1> r;
  // Evaluate whitened, then unwhiten (only for tests and diagnostics).
  Evaluate(parameters, r.data(), nullptr);
  return sqrt_info_.colPivHouseholderQr().solve(r);
}

bool ImuPreintegrationFactor::Evaluate(double const* const* parameters, double* residuals,
                                       double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> p_i(parameters[0]);
  const Eigen::Quaterniond q_i =
      Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized();
  const Eigen::Map<const Eigen::Vector3d> v_i(parameters[1]);
  const Eigen::Map<const Eigen::Vector3d> ba_i(parameters[2]);
  const Eigen::Map<const Eigen::Vector3d> bg_i(parameters[2] + 3);
  const Eigen::Map<const Eigen::Vector3d> p_j(parameters[3]);
  const Eigen::Quaterniond q_j =
      Eigen::Map<const Eigen::Quaterniond>(parameters[3] + 3).normalized();
  const Eigen::Map<const Eigen::Vector3d> v_j(parameters[4]);
  const Eigen::Map<const Eigen::Vector3d> ba_j(parameters[5]);
  const Eigen::Map<const Eigen::Vector3d> bg_j(parameters[5] + 3);

  const double qn_i = Eigen::Map<const Eigen::Vector4d>(parameters[0] + 3).norm();
  const double qn_j = Eigen::Map<const Eigen::Vector4d>(parameters[3] + 3).norm();
  const Eigen::Matrix3d R_i = q_i.toRotationMatrix();
  const Eigen::Matrix3d R_j = q_j.toRotationMatrix();
  const Eigen::Matrix3d Rt_i = R_i.transpose();
  const double dt = pre_.delta_t_s();
  const Eigen::Vector3d dba = ba_i - pre_.accel_bias_lin();
  const Eigen::Vector3d dbg = bg_i - pre_.gyro_bias_lin();

  // Bias-corrected deltas (first order, Forster et al. eq 44).
  const Eigen::Vector3d phi_bg = pre_.dR_dbg() * dbg;
  const Eigen::Matrix3d dR_c = pre_.delta_R() * so3::Exp(phi_bg);
  const Eigen::Vector3d dv_c = pre_.delta_v() + pre_.dv_dba() * dba + pre_.dv_dbg() * dbg;
  const Eigen::Vector3d dp_c = pre_.delta_p() + pre_.dp_dba() * dba + pre_.dp_dbg() * dbg;

  // Eq 14.
  const Eigen::Matrix3d E = dR_c.transpose() * Rt_i * R_j;
  const Eigen::Vector3d r_R = so3::Log(E);
  const Eigen::Vector3d v_term = Rt_i * (v_j - v_i - g_world_ * dt);
  const Eigen::Vector3d p_term = Rt_i * (p_j - p_i - v_i * dt - 0.5 * g_world_ * dt * dt);
  Eigen::Matrix<double, 15, 1> r;
  r.segment<3>(0) = r_R;
  r.segment<3>(3) = v_term - dv_c;
  r.segment<3>(6) = p_term - dp_c;
  r.segment<3>(9) = ba_j - ba_i;
  r.segment<3>(12) = bg_j - bg_i;
  Eigen::Map<Eigen::Matrix<double, 15, 1>> res(residuals);
  res = sqrt_info_ * r;

  if (jacobians == nullptr) return true;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d Jr_inv = so3::RightJacobianInverse(r_R);

  if (jacobians[0] != nullptr) {  // pose_i: [dp_i, dtheta_i]
    Matrix15x6 J = Matrix15x6::Zero();
    J.block<3, 3>(0, 3) = -Jr_inv * R_j.transpose() * R_i;
    J.block<3, 3>(3, 3) = so3::Hat(v_term);
    J.block<3, 3>(6, 0) = -Rt_i;
    J.block<3, 3>(6, 3) = so3::Hat(p_term);
    LocalPoseToAmbient(sqrt_info_ * J, q_i, qn_i, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {  // v_i
    Matrix15x3R J = Matrix15x3R::Zero();
    J.block<3, 3>(3, 0) = -Rt_i;
    J.block<3, 3>(6, 0) = -Rt_i * dt;
    Eigen::Map<Matrix15x3R> out(jacobians[1]);
    out = sqrt_info_ * J;
  }
  if (jacobians[2] != nullptr) {  // bias_i = [ba_i, bg_i]
    Matrix15x6R J = Matrix15x6R::Zero();
    J.block<3, 3>(0, 3) = -Jr_inv * E.transpose() * so3::RightJacobian(phi_bg) * pre_.dR_dbg();
    J.block<3, 3>(3, 0) = -pre_.dv_dba();
    J.block<3, 3>(3, 3) = -pre_.dv_dbg();
    J.block<3, 3>(6, 0) = -pre_.dp_dba();
    J.block<3, 3>(6, 3) = -pre_.dp_dbg();
    J.block<3, 3>(9, 0) = -I;
    J.block<3, 3>(12, 3) = -I;
    Eigen::Map<Matrix15x6R> out(jacobians[2]);
    out = sqrt_info_ * J;
  }
  if (jacobians[3] != nullptr) {  // pose_j
    Matrix15x6 J = Matrix15x6::Zero();
    J.block<3, 3>(0, 3) = Jr_inv;
    J.block<3, 3>(6, 0) = Rt_i;
    LocalPoseToAmbient(sqrt_info_ * J, q_j, qn_j, jacobians[3]);
  }
  if (jacobians[4] != nullptr) {  // v_j
    Matrix15x3R J = Matrix15x3R::Zero();
    J.block<3, 3>(3, 0) = Rt_i;
    Eigen::Map<Matrix15x3R> out(jacobians[4]);
    out = sqrt_info_ * J;
  }
  if (jacobians[5] != nullptr) {  // bias_j
    Matrix15x6R J = Matrix15x6R::Zero();
    J.block<3, 3>(9, 0) = I;
    J.block<3, 3>(12, 3) = I;
    Eigen::Map<Matrix15x6R> out(jacobians[5]);
    out = sqrt_info_ * J;
  }
  return true;
}

}  // namespace slam_mms
