// The outputs of MappingSystem: the final trajectory (the submaps' poses from the SubmapStore
// composed with their scans') and the final map (the submaps' clouds at their final poses,
// voxel-downsampled, with the first time and scan of each voxel).
#include <algorithm>
#include <cstdint>
#include <thread>
#include <utility>

#include "core/voxel_grid.hpp"
#include "core/voxel_sort.hpp"
#include "pipeline/mapping_system_impl.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/core/voxel_downsample.hpp"

namespace slam_mms {

Trajectory MappingSystem::FinalTrajectory() const {
  const Impl& m = *impl_;
  if (!m.loc) return m.pos_mapper.trajectory();
  std::vector<StampedPose> poses;
  for (const SubmapRecord& rec : m.loc->submaps()) {
    for (size_t j = 0; j < rec.T_submap_scan.size(); ++j) {
      StampedPose p;
      p.stamp = rec.scan_stamps[j];
      p.T_world_body = rec.T_world_submap * rec.T_submap_scan[j];
      // Rotate the submap-relative covariance (right perturbation: unchanged by left composition).
      p.cov_T_world_body = rec.cov_submap_scan[j];
      poses.push_back(p);
    }
  }
  std::sort(poses.begin(), poses.end(),
            [](const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; });
  Trajectory traj;
  for (const StampedPose& p : poses) {
    if (!traj.Add(p).ok()) continue;  // duplicates cannot happen; guard anyway
  }
  return traj;
}

PointCloud MappingSystem::FinalMap() const { return FinalMap(nullptr); }

namespace {

// Per voxel of VoxelDownsample(cloud, voxel_m), in its output order (voxels sorted by cell, the
// same internal::VoxelGrid cell of the float point): the stamps of the voxel's earliest point.
// Empty when `in` does not match `cloud`.
MapPointStamps EarliestPerVoxel(const PointCloud& cloud, const MapPointStamps& in, double voxel_m) {
  MapPointStamps out;
  if (in.size() != cloud.size() || in.scan_index.size() != cloud.size()) return out;
  const internal::VoxelGrid grid(voxel_m);
  std::vector<internal::CellIndex> keys;
  keys.reserve(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points()[i];
    internal::CellIndex k;
    // VoxelDownsample drops non-finite points and fails on out-of-range ones (then the caller
    // has no downsampled cloud to match).
    if (!grid.CellOf(p, &k.cell)) continue;
    k.index = static_cast<uint32_t>(i);
    keys.push_back(k);
  }
  internal::SortByCellThenIndex(&keys);  // VoxelDownsample's order
  for (size_t begin = 0; begin < keys.size();) {
    size_t end = begin + 1;
    size_t best = keys[begin].index;
    while (end < keys.size() && keys[end].cell == keys[begin].cell) {
      if (in.time_ns[keys[end].index] < in.time_ns[best]) best = keys[end].index;
      ++end;
    }
    out.time_ns.push_back(in.time_ns[best]);
    out.scan_index.push_back(in.scan_index[best]);
    begin = end;
  }
  return out;
}

}  // namespace

PointCloud MappingSystem::FinalMap(MapPointStamps* stamps) const {
  const Impl& m = *impl_;
  if (stamps != nullptr) stamps->clear();
  if (!m.loc) {
    return m.pos_mapper.Cloud(stamps);
  }
  PointCloud merged;
  MapPointStamps merged_stamps;
  bool all_stamped = stamps != nullptr;
  size_t total = 0;
  const std::vector<SubmapRecord>& records = m.loc->submaps();
  for (const SubmapRecord& rec : records) total += rec.cloud_size;
  merged.reserve(total);
  // One submap's cloud read (from memory, or back from the spill folder:
  // Localizer::Options::spill_dir) on a second thread while the previous one is placed.
  struct Loaded {
    StatusOr<PointCloud> cloud = PointCloud();
    MapPointStamps stamps;
  };
  auto load = [&](size_t k) {
    Loaded l;
    l.cloud = m.loc->SubmapCloud(records[k].id, Localizer::CloudKind::kMap,
                                 stamps != nullptr ? &l.stamps : nullptr);
    return l;
  };
  const bool prefetch = m.opt.num_threads > 1 && records.size() > 1;
  Loaded next;
  std::thread reader;
  if (!records.empty()) next = load(0);
  for (size_t k = 0; k < records.size(); ++k) {
    if (reader.joinable()) reader.join();
    Loaded cur = std::move(next);
    if (k + 1 < records.size()) {
      if (prefetch) {
        reader = std::thread([&next, &load, k] { next = load(k + 1); });
      } else {
        next = load(k + 1);
      }
    }
    const SubmapRecord& rec = records[k];
    if (!cur.cloud.ok()) {
      SLAM_MMS_LOG(kError) << "MappingSystem::FinalMap: submap " << rec.id
                           << " left out: " << cur.cloud.status().ToString();
      continue;
    }
    const PointCloud& cloud = *cur.cloud;
    const Eigen::Matrix3f R = rec.T_world_submap.linear().cast<float>();
    const Eigen::Vector3f t = rec.T_world_submap.translation().cast<float>();
    for (size_t i = 0; i < cloud.size(); ++i) {
      merged.Add(R * cloud.points()[i] + t, cloud.intensities()[i]);
    }
    if (all_stamped && cur.stamps.size() == cloud.size()) {
      merged_stamps.time_ns.insert(merged_stamps.time_ns.end(), cur.stamps.time_ns.begin(),
                                   cur.stamps.time_ns.end());
      merged_stamps.scan_index.insert(merged_stamps.scan_index.end(), cur.stamps.scan_index.begin(),
                                      cur.stamps.scan_index.end());
    } else {
      all_stamped = false;
    }
  }
  if (reader.joinable()) reader.join();
  // The centroids and the stamps are two independent sorts of the merged cloud: the stamps on a
  // second thread where asked for.
  MapPointStamps earliest;
  std::thread stamp_thread;
  if (all_stamped && m.opt.num_threads > 1) {
    stamp_thread =
        std::thread([&] { earliest = EarliestPerVoxel(merged, merged_stamps, m.opt.map_voxel_m); });
  } else if (all_stamped) {
    earliest = EarliestPerVoxel(merged, merged_stamps, m.opt.map_voxel_m);
  }
  auto down = VoxelDownsample(merged, m.opt.map_voxel_m);
  if (stamp_thread.joinable()) stamp_thread.join();
  if (!down.ok()) {
    if (all_stamped) *stamps = std::move(merged_stamps);
    return merged;
  }
  if (all_stamped) {
    if (earliest.size() == down->size()) {
      *stamps = std::move(earliest);
    } else {
      SLAM_MMS_LOG(kWarning) << "MappingSystem::FinalMap: point stamps do not match the map ("
                             << earliest.size() << " vs " << down->size() << "), left out";
    }
  }
  return std::move(down).value();
}

StatusOr<DriveResult> MappingSystem::ExportDriveResult() const {
  const Impl& m = *impl_;
  if (!m.finished) {
    return FailedPreconditionError("MappingSystem::ExportDriveResult: call Finish() first");
  }
  if (!m.loc || !m.level2) {
    return FailedPreconditionError(
        "MappingSystem::ExportDriveResult: mode has no submaps (kFull and kLidarOnly only)");
  }
  DriveResult out;
  SLAM_MMS_ASSIGN_OR_RETURN(out.origin, Origin());
  out.T_body_lidar = m.opt.T_body_lidar;
  const SubmapGraph& graph = m.level2->graph();
  for (const SubmapRecord& rec : m.loc->submaps()) {
    if (!graph.HasSubmap(rec.id)) continue;  // never finished (none after Finish)
    DriveSubmap sub;
    sub.id = rec.id;
    sub.start = rec.start;
    sub.end = rec.end;
    sub.T_world_submap = rec.T_world_submap;
    for (size_t j = 0; j < rec.T_submap_scan.size(); ++j) {
      SubmapScanPose s;
      s.submap = rec.id;
      s.scan_id = rec.scan_indices[j];
      s.stamp = rec.scan_stamps[j];
      s.T_submap_scan = rec.T_submap_scan[j];
      s.T_world_scan = rec.T_world_submap * rec.T_submap_scan[j];
      sub.scans.push_back(s);
    }
    sub.cov_submap_scan = rec.cov_submap_scan;
    SLAM_MMS_ASSIGN_OR_RETURN(sub.map_cloud,
                              m.loc->SubmapCloud(rec.id, Localizer::CloudKind::kMap));
    SLAM_MMS_ASSIGN_OR_RETURN(sub.registration_cloud,
                              m.loc->SubmapCloud(rec.id, Localizer::CloudKind::kRegistration));
    out.submaps.push_back(std::move(sub));
  }
  out.factors = graph.Factors();
  out.gnss_availability = GnssAvailability();
  return out;
}

std::vector<std::pair<Timestamp, Eigen::Isometry3d>> DriveResult::ScanPoses(
    const std::vector<Eigen::Isometry3d>* T_world_submap) const {
  std::vector<std::pair<Timestamp, Eigen::Isometry3d>> out;
  for (size_t k = 0; k < submaps.size(); ++k) {
    const DriveSubmap& sub = submaps[k];
    const Eigen::Isometry3d& T = T_world_submap != nullptr && k < T_world_submap->size()
                                     ? (*T_world_submap)[k]
                                     : sub.T_world_submap;
    for (const SubmapScanPose& s : sub.scans) out.emplace_back(s.stamp, T * s.T_submap_scan);
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

}  // namespace slam_mms
