// The glue between the stage objects of Localizer::ProcessScan (localizer.cpp runs them in order;
// numbers as in localizer.hpp): the input check, the scan's working values (ScanStep), the
// prediction, the integration and the bookkeeping after the stages.
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
  StartSubmap(T_world_body0, scan.stamp_start, scan.index, Eigen::Isometry3d::Identity(),
              Matrix6d::Identity() * noise::kAnchorPoseVariance);
  const Eigen::Vector3d v_submap0 = T_world_body0.linear().transpose() * motion.v_world_pos;
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

Status Localizer::Impl::IntegrateStage(const Scan& scan, const ScanStep& step,
                                       LocalizationResult* res) {
  const auto t0 = Clock::now();
  const Eigen::Isometry3d T_world_lidar = step.T_world_submap * step.T_submap_cur * T_body_lidar;
  auto stats = map.Integrate(deskewed.vnm, T_world_lidar, scan.stamp_start);
  if (!stats.ok()) return stats.status().WithContext("Localizer: surfel integration");
  res->num_surfels = stats->num_surfels;
  const Eigen::Isometry3d T_submap_lidar = step.T_submap_cur * T_body_lidar;
  clouds->Add(deskewed.cloud, scan.cloud.time_offsets_s(), scan.stamp_start.nanoseconds(),
              scan.index, T_submap_lidar, opt.map_max_range_m);
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
  registration.RecordPose(scan.stamp_start.nanoseconds(), res->T_world_body.translation());
  prev.T_submap = T_submap_cur;
  prev.stamp = scan.stamp_start;
  window.Advance(step.cur_state);
  prev.has_pos = motion.type == MotionFactorType::kOdometry;
  prev.pos_start = motion.T_world_body_pos_start;
  if (!window.use_imu_states() && motion.type == MotionFactorType::kOdometry) {
    prev.v_submap = step.T_world_submap.linear().transpose() * motion.v_world_pos;
  }
}

}  // namespace slam_mms
