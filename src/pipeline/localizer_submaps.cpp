// The submap life cycle of level 1 (Localizer::Impl): the start of a submap (and the retirement
// of old surfels), its close (clouds into the SubmapStore), and the cut every WT where a scan
// becomes the next submap's reference (with a new sliding window, WindowStage::Start).
#include <utility>  // first: a standard header brings in <features.h>, which defines __GLIBC__

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "pipeline/localizer_impl.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

void Localizer::Impl::StartSubmap(const Eigen::Isometry3d& T_world_submap, Timestamp stamp,
                                  int64_t scan_index, const Eigen::Isometry3d& T_prev_this,
                                  const Matrix6d& cov_prev_this) {
  const int32_t id = store.Start(T_world_submap, stamp, scan_index, T_prev_this, cov_prev_this).id;
  map.SetSubmapId(id);
  if (opt.per_submap_surfels) RetireOldSurfels(id);
  clouds->Clear();
}

void Localizer::Impl::RetireOldSurfels(int32_t current_id) {
  removed_scratch.clear();
  map.RemoveSubmapsExcept({current_id, current_id - 1},
                          opt.archive_surfels ? &removed_scratch : nullptr);
  const float threshold = static_cast<float>(opt.surfels.confidence_threshold);
  for (const Surfel& s : removed_scratch) {
    if (s.confidence > threshold) archived_surfels[s.submap_id].push_back(s);
  }
  removed_scratch.clear();
}

void Localizer::Impl::CloseCurrentSubmap() {
  if (store.empty() || store.current().finished) return;
  internal::SubmapCloudBuilder::Clouds built = clouds->Build();
  MapPointStamps stamps;
  stamps.time_ns = std::move(built.time_ns);
  stamps.scan_index = std::move(built.scan_index);
  store.FinishCurrent(std::move(built.map), std::move(stamps), std::move(built.registration));
  clouds->Clear();
#if defined(__GLIBC__)
  // A submap's clouds, grids and sort buffers (tens of MB) were just freed; glibc keeps such
  // blocks in its heaps, where later small allocations fragment them and the process's RSS
  // grows along the drive (measured: 420 MiB after 5 min of driving, 333 MiB with large
  // blocks returned at once). Returning the free pages once per submap keeps it flat.
  malloc_trim(0);
#endif
}

Status Localizer::Impl::CutSubmap(const Scan& scan, const Eigen::Isometry3d& T_world_submap,
                                  const Eigen::Isometry3d& T_submap_cur, LocalizationResult* res) {
  const Eigen::Isometry3d T_prev_this = T_submap_cur;
  const Matrix6d cov_prev_this = res->cov_T_world_body;
  // The scan belongs to the new submap (it is its reference), not to the old one.
  SubmapRecord& old = current();
  old.scan_indices.pop_back();
  old.scan_stamps.pop_back();
  old.T_submap_scan.pop_back();
  old.cov_submap_scan.pop_back();
  old.end = old.scan_stamps.back();
  CloseCurrentSubmap();
  StartSubmap(T_world_submap * T_submap_cur, scan.stamp_start, scan.index, T_prev_this,
              cov_prev_this);
  // Re-express the level-1 state in the new frame.
  const Eigen::Isometry3d T_new_old = T_submap_cur.inverse();
  motion_prior.Reframe(T_new_old);
  prev.T_submap = Eigen::Isometry3d::Identity();
  prev.v_submap = T_submap_cur.linear().transpose() * prev.v_submap;
  SLAM_MMS_RETURN_IF_ERROR(window.Start(prev.v_submap, prev.bias));
  clouds->Add(deskewed.cloud, scan.cloud.time_offsets_s(), scan.stamp_start.nanoseconds(),
              scan.index, T_body_lidar, opt.map_max_range_m);
  res->new_submap = true;
  res->submap_id = current().id;
  SLAM_MMS_LOG(kDebug) << "Localizer: submap " << current().id << " starts at scan " << scan.index;
  return OkStatus();
}

}  // namespace slam_mms
