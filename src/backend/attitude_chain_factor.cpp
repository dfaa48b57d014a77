#include "backend/attitude_chain_factor.hpp"

#include <ceres/autodiff_cost_function.h>
#include <ceres/rotation.h>

#include <Eigen/Geometry>

#include "backend/backend_math.hpp"
#include "backend/pose_block.hpp"

namespace slam_mms {
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

}  // namespace slam_mms
