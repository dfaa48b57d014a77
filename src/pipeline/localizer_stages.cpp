// The glue between the stage objects of Localizer::ProcessScan (localizer.cpp runs them in order;
// numbers as in localizer.hpp): the input check, the first submap, the scan's working values
// (ScanStep), the prediction, the bookkeeping after the stages and the submap cut, which hand
// the state the stages share (the previous scan, the motion prior's poses) from one to the next.
#include <string>

#include "pipeline/localizer_impl.hpp"
#include "pipeline/noise_model.hpp"
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
  integration.StartSubmap(T_world_body0, scan.stamp_start, scan.index,
                          Eigen::Isometry3d::Identity(),
                          Matrix6d::Identity() * noise::kAnchorPoseVariance, &map);
  const Eigen::Vector3d v_submap0 = T_world_body0.linear().transpose() * motion.v_world_pos;
  if (opt.mode == MappingMode::kLidarOnly && motion.type == MotionFactorType::kConstantVelocity &&
      v_submap0.allFinite() && v_submap0.squaredNorm() > 0.0) {
    // lidar_only started at the POS's velocity (Level1Options::lidar_only_initial_velocity), over
    // intervals of one scan's duration (a spinning LiDAR's scans follow each other).
    const double interval_s = scan.DurationSeconds() > 1e-3 ? scan.DurationSeconds() : 0.1;
    motion_prior.SeedVelocity(scan.stamp_start, v_submap0, interval_s);
  }
  prev.bias = motion.pos_bias;
  SLAM_MMS_RETURN_IF_ERROR(window.Start(v_submap0, prev.bias));
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

Status Localizer::Impl::RefineConstantVelocityDeskew(const Scan& scan, ScanStep* step,
                                                     LocalizationResult* res) {
  const double duration = scan.DurationSeconds();
  if (!opt.refine_constant_velocity_deskew || !step->constant_velocity_deskew ||
      !step->T_submap_reg || num_processed == 0 || !(prev.duration_s > 0.0) || !(duration > 0.0)) {
    return OkStatus();
  }
  // The registration holds the middle of the sweep (a wrong de-skew rate shears the scan
  // symmetrically about it); the previous scan's middle from its pose and its de-skew motion.
  const Eigen::Isometry3d T_submap_mid_prev =
      prev.T_submap * internal::ScalePose(prev.T_bstart_bend, 0.5);
  const Eigen::Isometry3d T_submap_mid =
      *step->T_submap_reg * internal::ScalePose(step->T_bstart_bend, 0.5);
  const double dt = scan.stamp_start.PlusSeconds(0.5 * duration)
                        .SecondsSince(prev.stamp.PlusSeconds(0.5 * prev.duration_s));
  if (!(dt > 1e-3)) return OkStatus();
  const Eigen::Isometry3d T_bstart_bend =
      internal::ScalePose(T_submap_mid_prev.inverse() * T_submap_mid, duration / dt);
  if (!T_bstart_bend.matrix().allFinite()) return OkStatus();
  // Registered again from the start pose that keeps the middle where it is.
  const Eigen::Isometry3d T_submap_start =
      T_submap_mid * internal::ScalePose(T_bstart_bend, 0.5).inverse();
  const Eigen::Isometry3d T_lidar_pred_lidar =
      step->T_world_lidar_pred.inverse() * step->T_world_submap * T_submap_start * T_body_lidar;
  const ScanStep first_step = *step;
  const LocalizationResult first_res = *res;
  SLAM_MMS_RETURN_IF_ERROR(deskew.DeskewWith(scan, T_bstart_bend, &deskewed, res));
  SLAM_MMS_RETURN_IF_ERROR(
      registration.Reregister(scan, model.model(), T_lidar_pred_lidar, &deskewed, step, res));
  if (step->T_submap_reg) {
    step->T_bstart_bend = T_bstart_bend;
    return OkStatus();
  }
  // Not usable the second time: the first de-skew and registration stand.
  const StageTimings timings = res->timings;
  *step = first_step;
  *res = first_res;
  res->timings = timings;
  return deskew.DeskewWith(scan, step->T_bstart_bend, &deskewed, res);
}

void Localizer::Impl::RecordScan(const Scan& scan, const ScanMotionInput& motion,
                                 const ScanStep& step, LocalizationResult* res) {
  const Eigen::Isometry3d& T_submap_cur = step.T_submap_cur;
  integration.Record(scan, step, res);
  ++num_processed;
  motion_prior.Record(scan.stamp_start, T_submap_cur);
  registration.RecordPose(scan.stamp_start.nanoseconds(), res->T_world_body.translation());
  prev.T_submap = T_submap_cur;
  prev.stamp = scan.stamp_start;
  window.Advance(step.cur_state);
  prev.has_pos = motion.type == MotionFactorType::kOdometry;
  prev.pos_start = motion.T_world_body_pos_start;
  prev.T_bstart_bend = step.T_bstart_bend;
  prev.duration_s = scan.DurationSeconds();
  if (!window.use_imu_states() && motion.type == MotionFactorType::kOdometry) {
    prev.v_submap = step.T_world_submap.linear().transpose() * motion.v_world_pos;
  }
}

Status Localizer::Impl::CutSubmap(const Scan& scan, const ScanStep& step, LocalizationResult* res) {
  const Eigen::Isometry3d& T_submap_cur = step.T_submap_cur;
  integration.Cut(scan, step, res->cov_T_world_body, &map);
  // Re-express the level-1 state in the new frame.
  const Eigen::Isometry3d T_new_old = T_submap_cur.inverse();
  motion_prior.Reframe(T_new_old);
  prev.T_submap = Eigen::Isometry3d::Identity();
  prev.v_submap = T_submap_cur.linear().transpose() * prev.v_submap;
  SLAM_MMS_RETURN_IF_ERROR(window.Start(prev.v_submap, prev.bias));
  integration.AddReferenceCloud(scan, deskewed.cloud);
  res->new_submap = true;
  res->submap_id = current().id;
  SLAM_MMS_LOG(kDebug) << "Localizer: submap " << current().id << " starts at scan " << scan.index;
  return OkStatus();
}

}  // namespace slam_mms
