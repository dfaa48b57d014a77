#include "pipeline/deskew_stage.hpp"

#include <utility>

namespace slam_mms::internal {

StatusOr<DeskewStage> DeskewStage::Create(const Localizer::Options& options,
                                          const RangeProjection& projection,
                                          const Eigen::Isometry3d& T_body_lidar) {
  DeskewStage stage;
  ScanDeskewer::Options deskew;
  static_cast<DeskewOptions&>(deskew) = options.deskew;
  deskew.num_threads = options.num_threads;
  SLAM_MMS_ASSIGN_OR_RETURN(stage.deskewer_, ScanDeskewer::Create(deskew));
  stage.projection_ = projection;
  stage.T_body_lidar_ = T_body_lidar;
  stage.range_image_ = std::make_unique<ParallelRangeImage>(options.num_threads);
  return stage;
}

Status DeskewStage::Deskew(const Scan& scan, const ScanMotionInput& motion,
                           const MotionPrior& prior, const Vector6d& bias, ScanStep* step,
                           DeskewedScan* out, LocalizationResult* res) {
  // The scan's own motion input: MotionPrior::DeskewMotion switches by motion.type, not by the
  // motion factor of step.pred.
  step->T_bstart_bend = prior.DeskewMotion(scan, motion, step->pred.T_submap, step->pred.v_submap,
                                           step->g_submap, bias, &step->constant_velocity_deskew);
  res->timings.deskew_ms = 0.0;
  return DeskewWith(scan, step->T_bstart_bend, out, res);
}

Status DeskewStage::DeskewWith(const Scan& scan, const Eigen::Isometry3d& T_bstart_bend,
                               DeskewedScan* out, LocalizationResult* res) {
  const auto t0 = Clock::now();
  SLAM_MMS_RETURN_IF_ERROR(deskewer_.Deskew(scan, T_bstart_bend, T_body_lidar_, &out->cloud));
  range_image_->ComputeVertexNormalMap(projection_, out->cloud.View(), &out->vnm);
  res->timings.deskew_ms += MsSince(t0);
  return OkStatus();
}

}  // namespace slam_mms::internal
