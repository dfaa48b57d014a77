// The motion prior of level 1 (Localizer::Impl): the prediction of a scan's pose, the de-skew
// motion over the scan, and the motion factor between consecutive scans (F_Odom, eq 12; F_Prein,
// eq 14; or the constant-velocity factor of LiDAR-only mode).
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
namespace {

/// Pose T scaled along its twist: Exp(s * Log(T)).
Eigen::Isometry3d ScalePose(const Eigen::Isometry3d& T, double s) {
  return se3::Exp(s * se3::Log(T));
}

}  // namespace

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

Prediction Localizer::Impl::Predict(const Scan& scan, const ScanMotionInput& motion,
                                    bool is_reference, const Eigen::Isometry3d& T_world_submap,
                                    const Eigen::Vector3d& g_submap) const {
  Prediction out;
  out.T_submap = T_submap_prev;
  out.v_submap = v_submap_prev;
  out.factor = is_reference ? MotionFactorType::kNone : motion.type;
  if (!is_reference) {
    const double dt = scan.stamp_start.SecondsSince(prev_stamp);
    if (out.factor == MotionFactorType::kOdometry && !has_pos_prev) {
      out.factor = use_imu_states && !motion.imu.empty() ? MotionFactorType::kPreintegration
                                                         : MotionFactorType::kConstantVelocity;
    }
    if (out.factor == MotionFactorType::kOdometry) {
      out.T_submap = T_submap_prev * (pos_prev_start.inverse() * motion.T_world_body_pos_start);
      out.v_submap = T_world_submap.linear().transpose() * motion.v_world_pos;
    } else if (out.factor == MotionFactorType::kPreintegration) {
      ImuPreintegration pre(opt.imu, bias_prev.head<3>(), bias_prev.tail<3>());
      const Status st = pre.IntegrateWindow(motion.imu, prev_stamp, scan.stamp_start);
      if (st.ok() && pre.num_samples() > 0) {
        const NavState e = pre.Predict(T_submap_prev, v_submap_prev, g_submap);
        out.T_submap = MakeIsometry(e.q_world_body, e.p_world);
        out.v_submap = e.v_world;
        out.pre = std::move(pre);
      } else {
        SLAM_MMS_LOG(kWarning) << "Localizer: scan " << scan.index
                               << ": IMU does not cover the scan interval (" << st.message()
                               << "); constant-velocity prediction instead";
        out.factor = MotionFactorType::kConstantVelocity;
      }
    }
    if (out.factor == MotionFactorType::kConstantVelocity) {
      // The prediction follows the last interval (it tracks acceleration; registration corrects
      // it, so it does not feed back like the de-skew).
      if (auto motion_cv = ConstantVelocityMotion(dt, 1)) out.T_submap = T_submap_prev * *motion_cv;
    }
  }
  return out;
}

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
                                    pos_prev_start.inverse() * motion.T_world_body_pos_start,
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
            ->AddRelativePoseFactor(prev_id, cur_state, T_submap_prev.inverse() * pred.T_submap,
                                    cov_motion, FactorKind::kMotion,
                                    RobustLoss::Huber(noise::kMotionHuberSigmas))
            .status());
  }
  return cov_motion;
}

std::optional<Eigen::Isometry3d> Localizer::Impl::ConstantVelocityMotion(double duration,
                                                                         size_t intervals) const {
  if (recent.size() < 2) return std::nullopt;
  const size_t first = recent.size() - 1 - std::min(intervals, recent.size() - 1);
  const auto& [t0, T0] = recent[first];
  const auto& [t1, T1] = recent.back();
  const double dt = t1.SecondsSince(t0);
  if (!(dt > 1e-3)) return std::nullopt;
  return ScalePose(T0.inverse() * T1, duration / dt);
}

Eigen::Isometry3d Localizer::Impl::DeskewMotion(const Scan& scan, const ScanMotionInput& motion,
                                                const Eigen::Isometry3d& T_submap_pred,
                                                const Eigen::Vector3d& v_submap_pred,
                                                const Eigen::Vector3d& g_submap) const {
  const double duration = scan.DurationSeconds();
  switch (motion.type) {
    case MotionFactorType::kOdometry:
      return motion.T_world_body_pos_start.inverse() * motion.T_world_body_pos_end;
    case MotionFactorType::kPreintegration: {
      ImuPreintegration pre(opt.imu, bias_prev.head<3>(), bias_prev.tail<3>());
      if (pre.IntegrateWindow(motion.imu, scan.stamp_start, scan.stamp_end).ok() &&
          pre.num_samples() > 0) {
        const NavState e = pre.Predict(T_submap_pred, v_submap_pred, g_submap);
        Eigen::Isometry3d T_end = MakeIsometry(e.q_world_body, e.p_world);
        return T_submap_pred.inverse() * T_end;
      }
      [[fallthrough]];
    }
    default:
      // The velocity over several scan intervals, not the last one: with the last interval, an
      // error in the estimated rotation between two scans bends the next de-skewed scan, whose
      // registration then errs the other way, and the alternating error grows (measured on the
      // simulated drive: 40 deg of roll error after 8 s). Averaging over
      // kDeskewVelocityIntervals intervals cancels that alternating mode.
      return ConstantVelocityMotion(duration, kDeskewVelocityIntervals)
          .value_or(Eigen::Isometry3d::Identity());
  }
}

}  // namespace slam_mms
