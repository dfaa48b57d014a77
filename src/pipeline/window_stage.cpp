// WindowStage: the motion factors (F_Odom, eq 12; F_Prein, eq 14; or the constant-velocity factor
// of LiDAR-only mode), F_Reg (eq 16) and the window solve of level 1.
#include "pipeline/window_stage.hpp"

#include <ceres/normal_prior.h>

#include <utility>

#include "backend/imu_preintegration_factor.hpp"
#include "pipeline/noise_model.hpp"
#include "pipeline/pose_covariance.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms::internal {

std::unique_ptr<ceres::CostFunction> MakeNormalPrior(const Eigen::VectorXd& mean,
                                                     const Eigen::VectorXd& sigma) {
  ceres::Matrix A = ceres::Matrix::Zero(mean.size(), mean.size());
  for (int i = 0; i < mean.size(); ++i) A(i, i) = 1.0 / sigma[i];
  ceres::Vector b = mean;
  return std::make_unique<ceres::NormalPrior>(A, b);
}

namespace {

/// The bias prior's sigmas [ba, bg] (noise_model.hpp).
Eigen::VectorXd BiasPriorSigma() {
  Eigen::VectorXd b_sigma(6);
  b_sigma << Eigen::Vector3d::Constant(noise::kBiasPriorSigmaAccelMps2),
      Eigen::Vector3d::Constant(noise::kBiasPriorSigmaGyroRadps);
  return b_sigma;
}

}  // namespace

WindowStage::WindowStage(const Localizer::Options& options)
    : odom_sigma_rot_rad_(options.odom_sigma_rot_rad),
      odom_sigma_trans_m_(options.odom_sigma_trans_m),
      cv_sigma_rot_rad_(options.cv_sigma_rot_rad),
      cv_sigma_trans_m_(options.cv_sigma_trans_m),
      use_imu_states_(options.mode == MappingMode::kFull) {
  static_cast<SlidingWindowOptions&>(window_options_) = options.window;
  window_options_.num_threads = options.num_threads;
}

Status WindowStage::Start(const Eigen::Vector3d& v_submap, const Vector6d& bias) {
  auto w = SlidingWindowGraph::Create(window_options_);
  if (!w.ok()) return w.status();
  window_ = std::make_unique<SlidingWindowGraph>(std::move(w).value());
  ref_id_ = next_id_++;
  StateInit init;
  init.keep = true;
  if (use_imu_states_) {
    init.v_frame = v_submap;
    init.imu_bias = bias;
  }
  SLAM_MMS_RETURN_IF_ERROR(window_->AddState(ref_id_, init));
  SLAM_MMS_RETURN_IF_ERROR(window_->SetBlockConstant({ref_id_, StateBlock::kPose}, true));
  if (use_imu_states_) {
    // The reference's velocity and biases carry over from the previous window (or the POS).
    auto v_prior = MakeNormalPrior(
        v_submap, Eigen::Vector3d::Constant(noise::kReferenceVelocityPriorSigmaMps));
    auto b_prior = MakeNormalPrior(bias, BiasPriorSigma());
    SLAM_MMS_RETURN_IF_ERROR(
        window_->AddCostFunction(std::move(v_prior), {{ref_id_, StateBlock::kVelocity}}).status());
    SLAM_MMS_RETURN_IF_ERROR(
        window_->AddCostFunction(std::move(b_prior), {{ref_id_, StateBlock::kBias}}).status());
  }
  prev_id_ = ref_id_;
  return OkStatus();
}

Status WindowStage::AddFactors(const Scan& scan, const ScanMotionInput& motion,
                               const PreviousScan& prev, ScanStep* step, LocalizationResult* res) {
  const auto t0 = Clock::now();
  const double dt = step->is_reference ? 0.0 : scan.stamp_start.SecondsSince(prev.stamp);
  step->cur_state = ref_id_;
  if (!step->is_reference) {
    const StateId cur_state = step->cur_state = next_id_++;
    StateInit init;
    init.T_frame_body = step->T_submap_reg.value_or(step->pred.T_submap);
    if (use_imu_states_) {
      init.v_frame = step->pred.v_submap;
      init.imu_bias = prev.bias;
    }
    SLAM_MMS_RETURN_IF_ERROR(window_->AddState(cur_state, init));
    SLAM_MMS_ASSIGN_OR_RETURN(const Matrix6d cov_motion,
                              AddMotionFactor(cur_state, motion, prev, *step, dt));
    if (step->T_submap_reg) {
      // F_Reg (eq 16): reference -> scan, checked against the motion prediction.
      MotionPrediction prediction;
      prediction.T_a_b = step->pred.T_submap;
      prediction.covariance = noise::kPredictionCovarianceInflation * cov_motion +
                              DiagonalPoseCovariance(noise::kPredictionSigmaFloorRotRad,
                                                     noise::kPredictionSigmaFloorTransM);
      // After a streak of rejections the prediction is what is off: a registration that is not
      // degenerate is taken as it is until one passes the gate again.
      const bool recover =
          window_options_.inconsistency_action == WindowInconsistencyAction::kReject &&
          rejected_in_a_row_ >= noise::kRejectedRegistrationsBeforeRecovery && !res->degenerate;
      prediction.enforce = !recover;
      auto outcome = window_->AddRelativePoseFactor(
          ref_id_, cur_state, *step->T_submap_reg, step->cov_reg, FactorKind::kRegistration,
          RobustLoss::Huber(noise::kRegistrationHuberSigmas), prediction);
      if (!outcome.ok()) return outcome.status().WithContext("Localizer: F_Reg");
      if (recover && !outcome->consistent) {
        SLAM_MMS_LOG(kInfo) << "Localizer: scan " << scan.index << ": registration taken after "
                            << rejected_in_a_row_
                            << " rejected in a row (the motion prediction is off: d2 = "
                            << outcome->mahalanobis_sq << ")";
      }
      res->registration_used = outcome->id.has_value();
      res->registration_downweighted = outcome->covariance_scale > 1.0;
      res->consistency_mahalanobis_sq = outcome->mahalanobis_sq;
      if (!res->registration_used) {
        SLAM_MMS_LOG(kDebug) << "Localizer: scan " << scan.index
                             << ": registration rejected by the consistency check (d2 = "
                             << outcome->mahalanobis_sq << ")";
      }
      // Recovery lasts until a registration passes the gate again.
      rejected_in_a_row_ = outcome->consistent ? 0 : rejected_in_a_row_ + 1;
    }
  }
  res->timings.factors_ms = MsSince(t0);
  return OkStatus();
}

StatusOr<Matrix6d> WindowStage::AddMotionFactor(StateId cur_state, const ScanMotionInput& motion,
                                                const PreviousScan& prev, const ScanStep& step,
                                                double dt) {
  const Prediction& pred = step.pred;
  Matrix6d cov_motion = DiagonalPoseCovariance(cv_sigma_rot_rad_, cv_sigma_trans_m_);
  if (pred.factor == MotionFactorType::kOdometry) {
    // F_Odom (eq 12) between consecutive scans: the POS relative motion.
    cov_motion = DiagonalPoseCovariance(odom_sigma_rot_rad_, odom_sigma_trans_m_);
    SLAM_MMS_RETURN_IF_ERROR(
        window_
            ->AddRelativePoseFactor(prev_id_, cur_state,
                                    prev.pos_start.inverse() * motion.T_world_body_pos_start,
                                    cov_motion, FactorKind::kMotion)
            .status());
    if (use_imu_states_) {
      const Eigen::Vector3d v_submap =
          step.T_world_submap.linear().transpose() * motion.v_world_pos;
      SLAM_MMS_RETURN_IF_ERROR(
          window_
              ->AddCostFunction(MakeNormalPrior(v_submap, Eigen::Vector3d::Constant(
                                                              noise::kPosVelocityPriorSigmaMps)),
                                {{cur_state, StateBlock::kVelocity}})
              .status());
      SLAM_MMS_RETURN_IF_ERROR(
          window_
              ->AddCostFunction(MakeNormalPrior(motion.pos_bias, BiasPriorSigma()),
                                {{cur_state, StateBlock::kBias}})
              .status());
    }
  } else if (pred.factor == MotionFactorType::kPreintegration) {
    // F_Prein (eq 14) with bias random walk between consecutive scans.
    auto factor = ImuPreintegrationFactor::Create(*pred.pre, step.g_submap);
    if (!factor.ok()) return factor.status().WithContext("Localizer: preintegration factor");
    SLAM_MMS_RETURN_IF_ERROR(
        window_
            ->AddCostFunction(std::move(factor).value(), {{prev_id_, StateBlock::kPose},
                                                          {prev_id_, StateBlock::kVelocity},
                                                          {prev_id_, StateBlock::kBias},
                                                          {cur_state, StateBlock::kPose},
                                                          {cur_state, StateBlock::kVelocity},
                                                          {cur_state, StateBlock::kBias}})
            .status());
    cov_motion = DiagonalPoseCovariance(
        noise::kPreintegrationSigmaRotRad + noise::kPreintegrationSigmaRotRadPerS * dt,
        noise::kPreintegrationSigmaTransM + noise::kPreintegrationSigmaTransMPerS * dt);
  } else {
    // LiDAR only: a weak constant-velocity factor keeps degenerate directions bounded.
    cov_motion = DiagonalPoseCovariance(cv_sigma_rot_rad_, cv_sigma_trans_m_);
    SLAM_MMS_RETURN_IF_ERROR(
        window_
            ->AddRelativePoseFactor(prev_id_, cur_state, prev.T_submap.inverse() * pred.T_submap,
                                    cov_motion, FactorKind::kMotion,
                                    RobustLoss::Huber(noise::kMotionHuberSigmas))
            .status());
  }
  return cov_motion;
}

Status WindowStage::Optimize(const Scan& scan, ScanStep* step, PreviousScan* prev,
                             LocalizationResult* res) {
  const auto t0 = Clock::now();
  step->T_submap_cur = Eigen::Isometry3d::Identity();
  if (!step->is_reference) {
    auto summary = window_->Solve();
    if (!summary.ok()) return summary.status().WithContext("Localizer: window solve");
    if (!summary->usable()) {
      SLAM_MMS_LOG(kWarning) << "Localizer: scan " << scan.index << ": window solve "
                             << SolveTerminationName(summary->termination) << ": "
                             << summary->message;
    }
    SLAM_MMS_ASSIGN_OR_RETURN(step->T_submap_cur, window_->Pose(step->cur_state));
    if (use_imu_states_) {
      auto v = window_->Velocity(step->cur_state);
      auto b = window_->ImuBias(step->cur_state);
      if (v.ok()) prev->v_submap = *v;
      if (b.ok()) prev->bias = *b;
    }
    auto cov = window_->PoseCovariance(step->cur_state);
    res->cov_T_world_body =
        cov.ok() ? *cov
                 : (step->T_submap_reg ? step->cov_reg
                                       : noise::kUnknownPoseVariance * Matrix6d::Identity());
  } else {
    res->cov_T_world_body = Matrix6d::Identity() * noise::kAnchorPoseVariance;
  }
  res->timings.optimize_ms = MsSince(t0);
  return OkStatus();
}

}  // namespace slam_mms::internal
