#include "pipeline/integration_stage.hpp"

#include <utility>  // first: a standard header brings in <features.h>, which defines __GLIBC__

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace slam_mms::internal {

StatusOr<IntegrationStage> IntegrationStage::Create(const Localizer::Options& options,
                                                    const Eigen::Isometry3d& T_body_lidar) {
  IntegrationStage stage;
  stage.submap_duration_s_ = options.submap_duration_s;
  stage.map_max_range_m_ = options.map_max_range_m;
  stage.per_submap_surfels_ = options.per_submap_surfels;
  stage.archive_surfels_ = options.archive_surfels;
  stage.archive_threshold_ = static_cast<float>(options.surfels.confidence_threshold);
  stage.T_body_lidar_ = T_body_lidar;
  stage.clouds_ = std::make_unique<SubmapCloudBuilder>(
      options.map_voxel_m, options.registration_voxel_m, /*asynchronous=*/options.num_threads > 1);
  auto store = SubmapStore::Create(options.spill_dir);
  if (!store.ok()) return store.status().WithContext("Localizer::Options::spill_dir");
  stage.store_ = std::move(store).value();
  return stage;
}

void IntegrationStage::StartSubmap(const Eigen::Isometry3d& T_world_submap, Timestamp stamp,
                                   int64_t scan_index, const Eigen::Isometry3d& T_prev_this,
                                   const Matrix6d& cov_prev_this, SurfelMap* map) {
  const int32_t id = store_.Start(T_world_submap, stamp, scan_index, T_prev_this, cov_prev_this).id;
  map->SetSubmapId(id);
  if (per_submap_surfels_) RetireOldSurfels(id, map);
  clouds_->Clear();
}

void IntegrationStage::RetireOldSurfels(int32_t current_id, SurfelMap* map) {
  removed_scratch_.clear();
  map->RemoveSubmapsExcept({current_id, current_id - 1},
                           archive_surfels_ ? &removed_scratch_ : nullptr);
  for (const Surfel& s : removed_scratch_) {
    if (s.confidence > archive_threshold_) archived_[s.submap_id].push_back(s);
  }
  removed_scratch_.clear();
}

Status IntegrationStage::Integrate(const Scan& raw, const DeskewedScan& scan, const ScanStep& step,
                                   SurfelMap* map, LocalizationResult* res) {
  const auto t0 = Clock::now();
  const Eigen::Isometry3d T_world_lidar = step.T_world_submap * step.T_submap_cur * T_body_lidar_;
  auto stats = map->Integrate(scan.vnm, T_world_lidar, raw.stamp_start);
  if (!stats.ok()) return stats.status().WithContext("Localizer: surfel integration");
  res->num_surfels = stats->num_surfels;
  const Eigen::Isometry3d T_submap_lidar = step.T_submap_cur * T_body_lidar_;
  clouds_->Add(scan.cloud, raw.cloud.time_offsets_s(), raw.stamp_start.nanoseconds(), raw.index,
               T_submap_lidar, map_max_range_m_);
  res->timings.integrate_ms = MsSince(t0);
  return OkStatus();
}

void IntegrationStage::Record(const Scan& scan, const ScanStep& step, LocalizationResult* res) {
  if (!step.is_reference) {
    SubmapRecord& rec = current();
    rec.scan_indices.push_back(scan.index);
    rec.scan_stamps.push_back(scan.stamp_start);
    rec.T_submap_scan.push_back(step.T_submap_cur);
    rec.cov_submap_scan.push_back(res->cov_T_world_body);
    rec.end = scan.stamp_start;
  }
  res->submap_id = current().id;
  res->T_world_body = step.T_world_submap * step.T_submap_cur;
}

bool IntegrationStage::CutDue(const Scan& scan, const ScanStep& step) const {
  return !step.is_reference &&
         scan.stamp_start.SecondsSince(store_.current().start) >= submap_duration_s_;
}

void IntegrationStage::Cut(const Scan& scan, const ScanStep& step, const Matrix6d& cov_prev_this,
                           SurfelMap* map) {
  // The scan belongs to the new submap (it is its reference), not to the old one.
  SubmapRecord& old = current();
  old.scan_indices.pop_back();
  old.scan_stamps.pop_back();
  old.T_submap_scan.pop_back();
  old.cov_submap_scan.pop_back();
  old.end = old.scan_stamps.back();
  CloseCurrentSubmap();
  StartSubmap(step.T_world_submap * step.T_submap_cur, scan.stamp_start, scan.index,
              step.T_submap_cur, cov_prev_this, map);
}

void IntegrationStage::AddReferenceCloud(const Scan& raw, const PointCloud& deskewed) {
  clouds_->Add(deskewed, raw.cloud.time_offsets_s(), raw.stamp_start.nanoseconds(), raw.index,
               T_body_lidar_, map_max_range_m_);
}

void IntegrationStage::CloseCurrentSubmap() {
  if (store_.empty() || store_.current().finished) return;
  SubmapCloudBuilder::Clouds built = clouds_->Build();
  MapPointStamps stamps;
  stamps.time_ns = std::move(built.time_ns);
  stamps.scan_index = std::move(built.scan_index);
  store_.FinishCurrent(std::move(built.map), std::move(stamps), std::move(built.registration));
  clouds_->Clear();
#if defined(__GLIBC__)
  // A submap's clouds, grids and sort buffers (tens of MB) were just freed; glibc keeps such
  // blocks in its heaps, where later small allocations fragment them and the process's RSS
  // grows along the drive (measured: 420 MiB after 5 min of driving, 333 MiB with large
  // blocks returned at once). Returning the free pages once per submap keeps it flat.
  malloc_trim(0);
#endif
}

Status IntegrationStage::SetSubmapPose(int32_t id, const Eigen::Isometry3d& T_world_submap,
                                       SurfelMap* map) {
  for (const SubmapRecord& rec : store_.submaps()) {
    if (rec.id != id) continue;
    // The surfels follow the submap.
    const Eigen::Isometry3d T_new_old = T_world_submap * rec.T_world_submap.inverse();
    map->TransformSubmap(id, T_new_old);
    if (auto it = archived_.find(id); it != archived_.end()) {
      const Eigen::Matrix3f R = T_new_old.linear().cast<float>();
      const Eigen::Vector3f t = T_new_old.translation().cast<float>();
      for (Surfel& s : it->second) TransformSurfel(R, t, &s);
    }
    break;
  }
  return store_.SetPose(id, T_world_submap);
}

}  // namespace slam_mms::internal
