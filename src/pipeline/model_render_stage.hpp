#pragma once
// ModelRenderStage: step 3 of Localizer::ProcessScan, the model view for projective association
// (paper §5.1.2). The surfels near the predicted LiDAR pose, of the current submap and, while it
// is young, of the previous one, are rendered at that pose into a vertex/normal map that the
// registration (step 4) and the moving-object filter compare the scan with.
//
// SuMa's threshold schedule: all surfels (confidence > ln(0.1 / 0.9)) at first, ramping up to
// Options::min_model_confidence (the stable ones) over the first 10 scans.
//
// Ownership: owns the model image and its id buffers (reused across scans); renders with the
// map's renderer (SurfelMap::renderer(), the one the map integrates with). Thread safety: not
// thread-safe.

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "pipeline/scan_step.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/localizer.hpp"
#include "slam_mms/surfel/surfel_map.hpp"
#include "slam_mms/surfel/vertex_normal_map.hpp"

namespace slam_mms::internal {

/// Fewer model surfels than this: no model, the scan is not registered.
inline constexpr size_t kMinModelSurfels = 100;

class ModelRenderStage {
 public:
  ModelRenderStage() = default;
  /// Uses options.model_radius_m, min_model_confidence and previous_submap_model_s.
  ModelRenderStage(const Localizer::Options& options, const Eigen::Isometry3d& T_body_lidar);

  /// Sets step->T_world_lidar_pred (from step->pred) and step->have_model, and renders the model
  /// of `submap` (the current one; `num_processed` scans so far) there when there are enough
  /// surfels. res: num_model_surfels and the time. `map` is not changed (its threads select).
  Status Render(const Scan& scan, const SubmapRecord& submap, int64_t num_processed, SurfelMap* map,
                ScanStep* step, LocalizationResult* res);

  /// The last model image (valid where the last Render set have_model).
  const VertexNormalMap& model() const { return model_vnm_; }
  /// The surfel ids of the last model (map ids), in render order.
  const std::vector<uint32_t>& model_ids() const { return model_ids_; }

 private:
  double model_radius_m_ = 0.0;
  float min_model_confidence_ = 0.0f;
  double previous_submap_model_s_ = 0.0;
  Eigen::Isometry3d T_body_lidar_ = Eigen::Isometry3d::Identity();
  std::vector<uint32_t> active_ids_;
  std::vector<uint32_t> model_ids_;
  VertexNormalMap model_vnm_;
};

}  // namespace slam_mms::internal
