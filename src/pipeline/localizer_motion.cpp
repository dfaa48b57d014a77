// The motion factor of level 1 (Localizer::Impl) between consecutive scans (F_Odom, eq 12;
// F_Prein, eq 14; or the constant-velocity factor of LiDAR-only mode); the prediction and the
// de-skew motion are the MotionPrior's (motion_prior.hpp).
#include <ceres/normal_prior.h>

#include <algorithm>
#include <utility>

#include "backend/imu_preintegration_factor.hpp"
#include "pipeline/localizer_impl.hpp"
#include "pipeline/noise_model.hpp"
#include "pipeline/pose_covariance.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

namespace noise = internal::noise;

namespace internal {
std::unique_ptr<ceres::CostFunction> MakeNormalPrior(const Eigen::VectorXd& mean,
                                                     const Eigen::VectorXd& sigma) {
  ceres::Matrix A = ceres::Matrix::Zero(mean.size(), mean.size());
  for (int i = 0; i < mean.size(); ++i) A(i, i) = 1.0 / sigma[i];
  ceres::Vector b = mean;
  return std::make_unique<ceres::NormalPrior>(A, b);
}
}  // namespace internal

using internal::MakeNormalPrior;

StatusOr<Matrix6d> Localizer::Impl::AddMotionFactor(StateId cur_state,
                                                    const ScanMotionInput& motion,
                                                    const Prediction& pred, double dt,
                                                    const Eigen::Isometry3d& T_world_submap,
                                                    const Eigen::Vector3d& g_submap) {
  Matrix6d cov_motion =
      internal::DiagonalPoseCovariance(opt.cv_sigma_rot_rad, opt.cv_sigma_trans_m);
  if (pred.factor == MotionFactorType::kOdometry) {
    // F_Odom (eq 12) between consecutive scans: the POS relative motion.
    cov_motion = internal::DiagonalPoseCovariance(opt.odom_sigma_rot_rad, opt.odom_sigma_trans_m);
    SLAM_MMS_RETURN_IF_ERROR(
        window
            ->AddRelativePoseFactor(prev_id, cur_state,
                                    prev.pos_start.inverse() * motion.T_world_body_pos_start,
                                    cov_motion, FactorKind::kMotion)
            .status());
    if (use_imu_states) {
      const Eigen::Vector3d v_submap = T_world_submap.linear().transpose() * motion.v_world_pos;
      SLAM_MMS_RETURN_IF_ERROR(
          window
              ->AddCostFunction(MakeNormalPrior(v_submap, Eigen::Vector3d::Constant(
                                                              noise::kPosVelocityPriorSigmaMps)),
                                {{cur_state, StateBlock::kVelocity}})
              .status());
      Eigen::VectorXd b_sigma(6);
      b_sigma << Eigen::Vector3d::Constant(noise::kBiasPriorSigmaAccelMps2),
          Eigen::Vector3d::Constant(noise::kBiasPriorSigmaGyroRadps);
      SLAM_MMS_RETURN_IF_ERROR(window
                                   ->AddCostFunction(MakeNormalPrior(motion.pos_bias, b_sigma),
                                                     {{cur_state, StateBlock::kBias}})
                                   .status());
    }
  } else if (pred.factor == MotionFactorType::kPreintegration) {
    // F_Prein (eq 14) with bias random walk between consecutive scans.
    auto factor = ImuPreintegrationFactor::Create(*pred.pre, g_submap);
    if (!factor.ok()) return factor.status().WithContext("Localizer: preintegration factor");
    SLAM_MMS_RETURN_IF_ERROR(
        window
            ->AddCostFunction(std::move(factor).value(), {{prev_id, StateBlock::kPose},
                                                          {prev_id, StateBlock::kVelocity},
                                                          {prev_id, StateBlock::kBias},
                                                          {cur_state, StateBlock::kPose},
                                                          {cur_state, StateBlock::kVelocity},
                                                          {cur_state, StateBlock::kBias}})
            .status());
    cov_motion = internal::DiagonalPoseCovariance(
        noise::kPreintegrationSigmaRotRad + noise::kPreintegrationSigmaRotRadPerS * dt,
        noise::kPreintegrationSigmaTransM + noise::kPreintegrationSigmaTransMPerS * dt);
  } else {
    // LiDAR only: a weak constant-velocity factor keeps degenerate directions bounded.
    cov_motion = internal::DiagonalPoseCovariance(opt.cv_sigma_rot_rad, opt.cv_sigma_trans_m);
    SLAM_MMS_RETURN_IF_ERROR(
        window
            ->AddRelativePoseFactor(prev_id, cur_state, prev.T_submap.inverse() * pred.T_submap,
                                    cov_motion, FactorKind::kMotion,
                                    RobustLoss::Huber(noise::kMotionHuberSigmas))
            .status());
  }
  return cov_motion;
}

}  // namespace slam_mms
