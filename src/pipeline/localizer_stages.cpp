// The stages of Localizer::ProcessScan (localizer.cpp runs them in order; numbers as in
// localizer.hpp). Each takes the scan's working values (ScanStep) from the stages before it and
// records its time in the result.
#include <algorithm>
#include <string>

#include "pipeline/localizer_impl.hpp"
#include "pipeline/noise_model.hpp"
#include "pipeline/pose_covariance.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

namespace noise = internal::noise;

Status Localizer::Impl::CheckScan(const Scan& scan, const ScanMotionInput& motion) const {
  if (scan.cloud.empty()) {
    return InvalidArgumentError("Localizer: scan '" + scan.source + "' (index " +
                                std::to_string(scan.index) + ") has no points");
  }
  if (started && !(prev.stamp < scan.stamp_start)) {
    return InvalidArgumentError("Localizer: scan '" + scan.source + "' starts at " +
                                scan.stamp_start.ToKittiString() +
                                ", not after the previous scan at " + prev.stamp.ToKittiString());
  }
  if (motion.type == MotionFactorType::kOdometry &&
      (!motion.T_world_body_pos_start.matrix().allFinite() ||
       !motion.T_world_body_pos_end.matrix().allFinite() || !motion.v_world_pos.allFinite())) {
    return InvalidArgumentError("Localizer: non-finite POS motion for scan '" + scan.source + "'");
  }
  return OkStatus();
}

Status Localizer::Impl::StartFirstSubmap(const Scan& scan, const ScanMotionInput& motion) {
  Eigen::Isometry3d T_world_body0 = initial_T_world_body;
  if (motion.type == MotionFactorType::kOdometry) T_world_body0 = motion.T_world_body_pos_start;
  StartSubmap(T_world_body0, scan.stamp_start, scan.index, Eigen::Isometry3d::Identity(),
              Matrix6d::Identity() * noise::kAnchorPoseVariance);
  const Eigen::Vector3d v_submap0 = T_world_body0.linear().transpose() * motion.v_world_pos;
  prev.bias = motion.pos_bias;
  SLAM_MMS_RETURN_IF_ERROR(StartWindow(v_submap0, prev.bias));
  started = true;
  prev.v_submap = v_submap0;
  return OkStatus();
}

ScanStep Localizer::Impl::BeginScan(const Scan& scan, const ScanMotionInput& motion) {
  ScanStep step;
  step.T_world_submap = current().T_world_submap;
  step.g_submap = step.T_world_submap.linear().transpose() * motion.g_world;
  step.is_reference =
      current().scan_indices.size() == 1 && current().scan_stamps.front() == scan.stamp_start;
  return step;
}

void Localizer::Impl::PredictStage(const Scan& scan, const ScanMotionInput& motion, ScanStep* step,
                                   LocalizationResult* res) const {
  const auto t0 = Clock::now();
  step->pred = motion_prior.Predict(scan, motion, step->is_reference, prev, step->T_world_submap,
                                    step->g_submap);
  res->motion_factor = step->pred.factor;
  res->timings.predict_ms = MsSince(t0);
}

Status Localizer::Impl::DeskewStage(const Scan& scan, const ScanMotionInput& motion,
                                    const ScanStep& step, LocalizationResult* res) {
  const auto t0 = Clock::now();
  const MotionFactorType factor_type = step.pred.factor;
  ScanMotionInput deskew_motion = motion;
  if (factor_type != MotionFactorType::kOdometry &&
      factor_type != MotionFactorType::kPreintegration &&
      motion.type == MotionFactorType::kOdometry) {
    deskew_motion.type = MotionFactorType::kOdometry;  // POS is fine for de-skew even without prev
  }
  const Eigen::Isometry3d T_bstart_bend = motion_prior.DeskewMotion(
      scan, deskew_motion, step.pred.T_submap, step.pred.v_submap, step.g_submap, prev.bias);
  SLAM_MMS_RETURN_IF_ERROR(deskewer.Deskew(scan, T_bstart_bend, T_body_lidar, &deskewed));
  range_image->ComputeVertexNormalMap(projection, deskewed.View(), &scan_vnm);
  res->timings.deskew_ms = MsSince(t0);
  return OkStatus();
}

Status Localizer::Impl::RenderStage(const Scan& scan, ScanStep* step, LocalizationResult* res) {
  const auto t0 = Clock::now();
  step->T_world_lidar_pred = step->T_world_submap * step->pred.T_submap * T_body_lidar;
  const int32_t cur_id = current().id;
  // SuMa's threshold schedule: all surfels at first, the stable ones after 10 scans.
  constexpr double kInitialThreshold = -2.1972245773362196;  // ln(0.1 / 0.9)
  const double ramp = std::min(1.0, static_cast<double>(num_processed) / 10.0);
  const float model_threshold =
      static_cast<float>(kInitialThreshold + ramp * (opt.min_model_confidence - kInitialThreshold));
  const bool with_previous =
      scan.stamp_start.SecondsSince(current().start) < opt.previous_submap_model_s;
  map.SelectActive(step->T_world_lidar_pred.translation(), opt.model_radius_m, model_threshold,
                   &active_ids);
  model_ids.clear();
  const auto& surfels = map.surfels();
  for (uint32_t id : active_ids) {
    const int32_t sid = surfels[id].submap_id;
    if (sid == cur_id || (with_previous && sid == cur_id - 1)) model_ids.push_back(id);
  }
  res->num_model_surfels = model_ids.size();
  step->have_model = model_ids.size() >= 100;
  if (step->have_model) {
    SLAM_MMS_RETURN_IF_ERROR(renderer->Render(SurfelRenderInput::Subset(surfels, model_ids),
                                              step->T_world_lidar_pred, &model_vnm));
  }
  res->timings.render_ms = MsSince(t0);
  return OkStatus();
}

Status Localizer::Impl::RegisterStage(const Scan& scan, ScanStep* step, LocalizationResult* res) {
  const auto t0 = Clock::now();
  if (step->have_model && !step->is_reference) {
    // Moving objects (DynamicObjectOptions), judged at the prediction where it comes from the POS
    // or the IMU. A constant-velocity prediction (LiDAR only, a submap's second scan) is not good
    // enough to judge by, nor is a registration that moving objects may have pulled.
    const MotionFactorType factor = step->pred.factor;
    if (opt.dynamic.enabled &&
        (factor == MotionFactorType::kOdometry || factor == MotionFactorType::kPreintegration)) {
      const Eigen::Matrix3d R_submap_lidar = step->pred.T_submap.linear() * T_body_lidar.linear();
      const Eigen::Vector3f up_lidar =
          (-(R_submap_lidar.transpose() * step->g_submap).normalized()).cast<float>();
      if (up_lidar.allFinite()) {
        const internal::DynamicObjectStats st =
            dynamic.Detect(scan_vnm, model_vnm, up_lidar, map.surfels(),
                           travel.StampBefore(opt.dynamic.max_model_travel_m));
        if (st.num_moving > 0) {
          dynamic.Apply(&scan_vnm);
          map.RemoveSurfels(dynamic.seen_through());
          dynamic.MaskPoints(&deskewed);
        }
        res->num_moving_objects = st.num_moving;
        res->num_moving_pixels = st.num_masked_pixels;
      }
    }
    auto reg = icp.Align(scan_vnm, model_vnm, Eigen::Isometry3d::Identity());
    if (!reg.ok()) return reg.status().WithContext("Localizer: scan " + std::to_string(scan.index));
    const RegistrationResult& r = *reg;
    res->registered = true;
    res->termination = r.termination;
    res->num_inliers = r.num_inliers;
    res->inlier_ratio = r.inlier_ratio;
    res->rms_residual_m = r.rms_residual_m;
    res->icp_iterations = r.iterations;
    res->degenerate = r.degeneracy.degenerate;
    res->degeneracy_axis_information = r.degeneracy.axis_information;
    if (r.IsUsable() && r.inlier_ratio >= opt.min_inlier_ratio &&
        r.T_target_source.matrix().allFinite()) {
      const Eigen::Isometry3d T_world_body =
          step->T_world_lidar_pred * r.T_target_source * T_lidar_body;
      step->T_submap_reg = step->T_world_submap.inverse() * T_world_body;
      // Right perturbation of T_world_lidar -> of T_world_body: Ad(T_body_lidar).
      const Matrix6d Ad = se3::Adjoint(T_body_lidar);
      Matrix6d& cov_reg = step->cov_reg;
      cov_reg = opt.reg_cov_scale * (Ad * r.covariance * Ad.transpose());
      cov_reg.diagonal() +=
          internal::DiagonalPoseCovariance(opt.reg_sigma_floor_rot_rad, opt.reg_sigma_floor_trans_m)
              .diagonal();
      cov_reg = 0.5 * (cov_reg + cov_reg.transpose()).eval();
    }
  }
  res->timings.register_ms = MsSince(t0);
  return OkStatus();
}

Status Localizer::Impl::FactorStage(const Scan& scan, const ScanMotionInput& motion, ScanStep* step,
                                    LocalizationResult* res) {
  const auto t0 = Clock::now();
  const double dt = step->is_reference ? 0.0 : scan.stamp_start.SecondsSince(prev.stamp);
  step->cur_state = ref_id;
  if (!step->is_reference) {
    const StateId cur_state = step->cur_state = next_id++;
    StateInit init;
    init.T_frame_body = step->T_submap_reg.value_or(step->pred.T_submap);
    if (use_imu_states) {
      init.v_frame = step->pred.v_submap;
      init.imu_bias = prev.bias;
    }
    SLAM_MMS_RETURN_IF_ERROR(window->AddState(cur_state, init));
    SLAM_MMS_ASSIGN_OR_RETURN(
        const Matrix6d cov_motion,
        AddMotionFactor(cur_state, motion, step->pred, dt, step->T_world_submap, step->g_submap));
    if (step->T_submap_reg) {
      // F_Reg (eq 16): reference -> scan, checked against the motion prediction.
      MotionPrediction prediction;
      prediction.T_a_b = step->pred.T_submap;
      prediction.covariance = noise::kPredictionCovarianceInflation * cov_motion +
                              internal::DiagonalPoseCovariance(noise::kPredictionSigmaFloorRotRad,
                                                               noise::kPredictionSigmaFloorTransM);
      auto outcome = window->AddRelativePoseFactor(
          ref_id, cur_state, *step->T_submap_reg, step->cov_reg, FactorKind::kRegistration,
          RobustLoss::Huber(noise::kRegistrationHuberSigmas), prediction);
      if (!outcome.ok()) return outcome.status().WithContext("Localizer: F_Reg");
      res->registration_used = outcome->id.has_value();
      res->registration_downweighted = outcome->covariance_scale > 1.0;
      res->consistency_mahalanobis_sq = outcome->mahalanobis_sq;
      if (!res->registration_used) {
        SLAM_MMS_LOG(kDebug) << "Localizer: scan " << scan.index
                             << ": registration rejected by the consistency check (d2 = "
                             << outcome->mahalanobis_sq << ")";
      }
    }
  }
  res->timings.factors_ms = MsSince(t0);
  return OkStatus();
}

Status Localizer::Impl::OptimizeStage(const Scan& scan, ScanStep* step, LocalizationResult* res) {
  const auto t0 = Clock::now();
  step->T_submap_cur = Eigen::Isometry3d::Identity();
  if (!step->is_reference) {
    auto summary = window->Solve();
    if (!summary.ok()) return summary.status().WithContext("Localizer: window solve");
    if (!summary->usable()) {
      SLAM_MMS_LOG(kWarning) << "Localizer: scan " << scan.index << ": window solve "
                             << SolveTerminationName(summary->termination) << ": "
                             << summary->message;
    }
    SLAM_MMS_ASSIGN_OR_RETURN(step->T_submap_cur, window->Pose(step->cur_state));
    if (use_imu_states) {
      auto v = window->Velocity(step->cur_state);
      auto b = window->ImuBias(step->cur_state);
      if (v.ok()) prev.v_submap = *v;
      if (b.ok()) prev.bias = *b;
    }
    auto cov = window->PoseCovariance(step->cur_state);
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

Status Localizer::Impl::IntegrateStage(const Scan& scan, const ScanStep& step,
                                       LocalizationResult* res) {
  const auto t0 = Clock::now();
  const Eigen::Isometry3d T_world_lidar = step.T_world_submap * step.T_submap_cur * T_body_lidar;
  auto stats = map.Integrate(scan_vnm, T_world_lidar, scan.stamp_start);
  if (!stats.ok()) return stats.status().WithContext("Localizer: surfel integration");
  res->num_surfels = stats->num_surfels;
  const Eigen::Isometry3d T_submap_lidar = step.T_submap_cur * T_body_lidar;
  clouds->Add(deskewed, scan.cloud.time_offsets_s(), scan.stamp_start.nanoseconds(), scan.index,
              T_submap_lidar, opt.map_max_range_m);
  res->timings.integrate_ms = MsSince(t0);
  return OkStatus();
}

void Localizer::Impl::RecordScan(const Scan& scan, const ScanMotionInput& motion,
                                 const ScanStep& step, LocalizationResult* res) {
  const Eigen::Isometry3d& T_submap_cur = step.T_submap_cur;
  if (!step.is_reference) {
    SubmapRecord& rec = current();
    rec.scan_indices.push_back(scan.index);
    rec.scan_stamps.push_back(scan.stamp_start);
    rec.T_submap_scan.push_back(T_submap_cur);
    rec.cov_submap_scan.push_back(res->cov_T_world_body);
    rec.end = scan.stamp_start;
  }
  res->submap_id = current().id;
  res->T_world_body = step.T_world_submap * T_submap_cur;
  ++num_processed;
  motion_prior.Record(scan.stamp_start, T_submap_cur);
  travel.Add(scan.stamp_start.nanoseconds(), res->T_world_body.translation(),
             opt.dynamic.max_model_travel_m);
  prev.T_submap = T_submap_cur;
  prev.stamp = scan.stamp_start;
  prev_id = step.cur_state;
  prev.has_pos = motion.type == MotionFactorType::kOdometry;
  prev.pos_start = motion.T_world_body_pos_start;
  if (!use_imu_states && motion.type == MotionFactorType::kOdometry) {
    prev.v_submap = step.T_world_submap.linear().transpose() * motion.v_world_pos;
  }
}

}  // namespace slam_mms
