#pragma once
// SubmapSource: what level 1 shows level 2 (issue #19's one-way flow). Level 1 (the Localizer)
// owns the submaps: their records (poses, scans, clouds) and spill files. Level 2
// (SubmapManager) reads them through this read-only interface and returns SubmapPoseUpdate
// values; the host (MappingSystem) applies them to level 1 (Localizer::SetSubmapPose). Level 2
// never calls level 1 back.
//
// Thread safety: the interface is const; an implementation says what it allows.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/pipeline/map_point_stamps.hpp"

namespace slam_mms {

/// A finished or current submap as level 1 hands it to level 2.
struct SubmapRecord {
  int32_t id = 0;
  Eigen::Isometry3d T_world_submap = Eigen::Isometry3d::Identity();  ///< Level-1 estimate.
  Timestamp start;
  Timestamp end;
  std::vector<int64_t> scan_indices;
  std::vector<Timestamp> scan_stamps;
  std::vector<Eigen::Isometry3d> T_submap_scan;  ///< Body poses in the submap frame.
  std::vector<Matrix6d> cov_submap_scan;
  /// Relative pose of the previous submap's reference to this one's (the reckon chain, eq 21), and
  /// its covariance; identity for the first.
  Eigen::Isometry3d T_prev_this = Eigen::Isometry3d::Identity();
  Matrix6d cov_prev_this = Matrix6d::Identity();
  /// De-skewed points of the submap's scans in the submap frame, voxel-downsampled (map output).
  /// Empty once spilled to `cloud_file` (Localizer::Options::spill_dir): read it with
  /// SubmapSource::SubmapCloud, which serves both cases.
  PointCloud cloud;
  /// Per point of `cloud`: the time and scan of the voxel's first point (empty once spilled, like
  /// `cloud`; SubmapCloud returns them).
  MapPointStamps cloud_stamps;
  /// A coarser cloud for map-to-map registration and loop closure; spilled like `cloud` once the
  /// submap is two behind the current one.
  PointCloud registration_cloud;
  std::filesystem::path cloud_file;               ///< Empty while `cloud` is in memory.
  std::filesystem::path registration_cloud_file;  ///< Empty while in memory.
  size_t cloud_size = 0;                          ///< Points of the map cloud, wherever it is.
  bool finished = false;
};

/// A level-2 estimate for one submap: move it (and its surfels) to T_world_submap.
struct SubmapPoseUpdate {
  int32_t id = 0;
  Eigen::Isometry3d T_world_submap = Eigen::Isometry3d::Identity();
};

class SubmapSource {
 public:
  enum class CloudKind { kMap, kRegistration };
  virtual ~SubmapSource() = default;
  /// Submaps so far, in id order (the last one may be unfinished).
  virtual const std::vector<SubmapRecord>& submaps() const = 0;
  /// A submap's map or registration cloud (submap frame), wherever it is kept. NotFound for an
  /// unknown id; the error of a failed read otherwise.
  virtual StatusOr<PointCloud> SubmapCloud(int32_t id, CloudKind kind) const = 0;
};

}  // namespace slam_mms
