#pragma once
// SubmapStore: the one owner of level 1's submaps (issue #19): their records (pose, scans with
// their poses in the submap frame, time span, reckon to the previous submap), their map and
// registration clouds, the spill folder those go to on long drives, and their retirement. The
// Localizer writes it (Start, the current record, Finish); level 2 reads it as a SubmapSource;
// the host moves submaps with SetPose; the final trajectory and map are read from it.
//
// Spilling (Localizer::Options::spill_dir): a finished submap's map cloud goes to a file at once
// (level 2 reads only the final map from it); its registration cloud when the submap is two
// behind the current one (level 2 registers each submap with the previous one first). A failed
// write keeps the cloud in memory (logged); nothing is lost.
//
// Thread safety: not thread-safe; const methods may run concurrently with each other.

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "pipeline/cloud_file.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/pipeline/map_point_stamps.hpp"
#include "slam_mms/pipeline/submap_source.hpp"

namespace slam_mms::internal {

class SubmapStore final : public SubmapSource {
 public:
  /// Clouds stay in memory.
  SubmapStore() = default;
  /// Spills into a private folder created inside `spill_dir` (empty: no spilling); the folder is
  /// removed with the store. Unavailable naming the folder when it cannot be created.
  static StatusOr<SubmapStore> Create(const std::filesystem::path& spill_dir);
  SubmapStore(SubmapStore&&) noexcept = default;
  SubmapStore& operator=(SubmapStore&&) noexcept = default;

  // ---- SubmapSource ----------------------------------------------------------------------------
  const std::vector<SubmapRecord>& submaps() const override { return submaps_; }
  StatusOr<PointCloud> SubmapCloud(int32_t id, CloudKind kind) const override;
  /// The same; `stamps` (may be null) gets the map cloud's MapPointStamps (empty for
  /// kRegistration).
  StatusOr<PointCloud> SubmapCloud(int32_t id, CloudKind kind, MapPointStamps* stamps) const;

  // ---- level 1 ---------------------------------------------------------------------------------
  /// A new current submap whose reference is the scan `scan_index` at `stamp` (identity pose in
  /// the submap, covariance 1e-8 I); its id is the last one + 1 (0 first).
  SubmapRecord& Start(const Eigen::Isometry3d& T_world_submap, Timestamp stamp, int64_t scan_index,
                      const Eigen::Isometry3d& T_prev_this, const Matrix6d& cov_prev_this);
  bool empty() const { return submaps_.empty(); }
  /// The current (last) submap; the store must not be empty.
  SubmapRecord& current() { return submaps_.back(); }
  const SubmapRecord& current() const { return submaps_.back(); }
  /// Finishes the current submap with its clouds and spills as described above. No-op when it is
  /// finished already (or there is none).
  void FinishCurrent(PointCloud map_cloud, MapPointStamps stamps, PointCloud registration_cloud);

  // ---- host ------------------------------------------------------------------------------------
  /// Sets a submap's pose. NotFound for an unknown id.
  Status SetPose(int32_t id, const Eigen::Isometry3d& T_world_submap);
  /// Frees a submap's map cloud (and registration cloud unless kept), files included.
  void ReleaseClouds(int32_t id, bool keep_registration_cloud);
  /// The private spill folder (empty without spilling).
  const std::filesystem::path& spill_folder() const { return spill_.path(); }

 private:
  /// Moves one cloud of `rec` to a file in the spill folder; on failure it stays in memory.
  void Spill(SubmapRecord& rec, CloudKind kind);
  SubmapRecord* Find(int32_t id);

  std::vector<SubmapRecord> submaps_;
  SpillFolder spill_;
};

}  // namespace slam_mms::internal
