#pragma once
// IntegrationStage: step 7 of Localizer::ProcessScan and the submap life cycle of level 1. The
// scan at its optimized pose is fused into the surfel map (SuMa's update, paper §5.1.2) and added
// to the current submap's map and registration clouds; its pose goes into the submap's record;
// every WT (Options::submap_duration_s) a scan becomes the reference of a new submap (paper §5.1:
// T_world_scan = T_world_submap * T_submap_scan). A finished submap's clouds go into the
// SubmapStore; with per_submap_surfels, submaps two behind leave the live surfel map (their
// stable surfels archived when asked).
//
// Ownership: owns the submaps (SubmapStore: records, clouds, spill files; the one owner), the
// current submap's cloud builder and the archived surfels; the surfel map is the caller's.
// Thread safety: not thread-safe (the cloud builder works on its own thread, see
// SubmapCloudBuilder).

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "pipeline/scan_step.hpp"
#include "pipeline/submap_cloud_builder.hpp"
#include "pipeline/submap_store.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/localizer.hpp"
#include "slam_mms/surfel/surfel_map.hpp"

namespace slam_mms::internal {

class IntegrationStage {
 public:
  IntegrationStage() = default;
  /// Uses options.spill_dir, map_voxel_m, registration_voxel_m, map_max_range_m, num_threads (>
  /// 1: the clouds are built asynchronously), submap_duration_s, per_submap_surfels,
  /// archive_surfels and surfels.confidence_threshold. The SubmapStore's error (with the field's
  /// name) where the spill folder cannot be created.
  static StatusOr<IntegrationStage> Create(const Localizer::Options& options,
                                           const Eigen::Isometry3d& T_body_lidar);

  /// A new submap at T_world_submap whose reference is scan `scan_index` at `stamp`
  /// (T_prev_this, cov_prev_this: from the previous submap's reference); new surfels of `map` go
  /// into it, and with per_submap_surfels the submaps two behind leave `map`.
  void StartSubmap(const Eigen::Isometry3d& T_world_submap, Timestamp stamp, int64_t scan_index,
                   const Eigen::Isometry3d& T_prev_this, const Matrix6d& cov_prev_this,
                   SurfelMap* map);

  /// Step 7: fuses `scan` (de-skewed, its image) at step.T_submap_cur into `map` and the current
  /// submap's clouds; res: num_surfels and the time.
  Status Integrate(const Scan& raw, const DeskewedScan& scan, const ScanStep& step, SurfelMap* map,
                   LocalizationResult* res);

  /// The scan's pose (step.T_submap_cur, covariance res->cov_T_world_body) into the current
  /// submap's record (a reference is there already); res: submap_id and T_world_body.
  void Record(const Scan& scan, const ScanStep& step, LocalizationResult* res);

  /// The scan, recorded, is due to start a new submap (WT after the current one's start).
  bool CutDue(const Scan& scan, const ScanStep& step) const;
  /// The cut: the recorded scan leaves the current submap, which is finished, and starts a new
  /// one at its pose (T_prev_this = step.T_submap_cur with covariance cov_prev_this).
  void Cut(const Scan& scan, const ScanStep& step, const Matrix6d& cov_prev_this, SurfelMap* map);
  /// The new submap's reference scan (de-skewed, LiDAR frame) into its clouds, after Cut.
  void AddReferenceCloud(const Scan& raw, const PointCloud& deskewed);

  /// Finishes the current submap (its clouds into the store); nothing when there is none or it is
  /// finished.
  void CloseCurrentSubmap();

  /// Moves submap `id` to T_world_submap: its live surfels in `map`, its archived ones and its
  /// record. InvalidArgument / NotFound as SubmapStore::SetPose.
  Status SetSubmapPose(int32_t id, const Eigen::Isometry3d& T_world_submap, SurfelMap* map);

  SubmapStore& store() { return store_; }
  const SubmapStore& store() const { return store_; }
  SubmapRecord& current() { return store_.current(); }
  /// Stable surfels of the submaps that left the live map, by submap id.
  const std::map<int32_t, std::vector<Surfel>>& archived_surfels() const { return archived_; }

 private:
  /// Takes the surfels of submaps older than current_id - 1 out of `map` (archiving the stable
  /// ones when asked).
  void RetireOldSurfels(int32_t current_id, SurfelMap* map);

  double submap_duration_s_ = 0.0;
  double map_max_range_m_ = 0.0;
  bool per_submap_surfels_ = false;
  bool archive_surfels_ = false;
  float archive_threshold_ = 0.0f;
  Eigen::Isometry3d T_body_lidar_ = Eigen::Isometry3d::Identity();
  SubmapStore store_;
  /// The current submap's map and registration clouds (accumulated off the critical path).
  std::unique_ptr<SubmapCloudBuilder> clouds_;
  std::map<int32_t, std::vector<Surfel>> archived_;
  std::vector<Surfel> removed_scratch_;
};

}  // namespace slam_mms::internal
