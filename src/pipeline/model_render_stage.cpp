#include "pipeline/model_render_stage.hpp"

#include <algorithm>

namespace slam_mms::internal {

ModelRenderStage::ModelRenderStage(const Localizer::Options& options,
                                   const Eigen::Isometry3d& T_body_lidar)
    : model_radius_m_(options.model_radius_m),
      min_model_confidence_(options.min_model_confidence),
      previous_submap_model_s_(options.previous_submap_model_s),
      T_body_lidar_(T_body_lidar) {}

Status ModelRenderStage::Render(const Scan& scan, const SubmapRecord& submap, int64_t num_processed,
                                SurfelMap* map, ScanStep* step, LocalizationResult* res) {
  const auto t0 = Clock::now();
  step->T_world_lidar_pred = step->T_world_submap * step->pred.T_submap * T_body_lidar_;
  const int32_t cur_id = submap.id;
  // SuMa's threshold schedule: all surfels at first, the stable ones after 10 scans.
  constexpr double kInitialThreshold = -2.1972245773362196;  // ln(0.1 / 0.9)
  const double ramp = std::min(1.0, static_cast<double>(num_processed) / 10.0);
  const float model_threshold =
      static_cast<float>(kInitialThreshold + ramp * (min_model_confidence_ - kInitialThreshold));
  const bool with_previous = scan.stamp_start.SecondsSince(submap.start) < previous_submap_model_s_;
  map->SelectActive(step->T_world_lidar_pred.translation(), model_radius_m_, model_threshold,
                    &active_ids_);
  model_ids_.clear();
  const auto& surfels = map->surfels();
  for (uint32_t id : active_ids_) {
    const int32_t sid = surfels[id].submap_id;
    if (sid == cur_id || (with_previous && sid == cur_id - 1)) model_ids_.push_back(id);
  }
  res->num_model_surfels = model_ids_.size();
  step->have_model = model_ids_.size() >= kMinModelSurfels;
  if (step->have_model) {
    SLAM_MMS_RETURN_IF_ERROR(map->renderer().Render(SurfelRenderInput::Subset(surfels, model_ids_),
                                                    step->T_world_lidar_pred, &model_vnm_));
  }
  res->timings.render_ms = MsSince(t0);
  return OkStatus();
}

}  // namespace slam_mms::internal
