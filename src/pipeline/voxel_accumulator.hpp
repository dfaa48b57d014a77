#pragma once
// VoxelAccumulator: an incremental voxel grid (centroid and mean intensity per voxel), used to
// build the map clouds scan by scan without keeping the scans. Private to the pipeline.

#include <Eigen/Geometry>
#include <cstdint>
#include <unordered_map>

#include "slam_mms/core/point_cloud.hpp"

namespace slam_mms::internal {

class VoxelAccumulator {
 public:
  explicit VoxelAccumulator(double voxel_m = 0.1) : inv_voxel_(1.0 / voxel_m) {}

  /// Adds the points of `cloud` (frame c) transformed by T_frame_c, those within max_range_m of
  /// the cloud's origin.
  void Add(const PointCloud& cloud, const Eigen::Isometry3d& T_frame_c, double max_range_m);
  /// The centroids (frame of the accumulator), sorted by voxel key (deterministic).
  PointCloud Cloud() const;
  size_t size() const { return voxels_.size(); }
  size_t MemoryBytes() const { return voxels_.size() * (sizeof(Voxel) + sizeof(uint64_t) + 16); }
  void Clear() { voxels_.clear(); }

 private:
  struct Voxel {
    double x = 0, y = 0, z = 0;
    float intensity = 0;
    uint32_t count = 0;
  };
  double inv_voxel_;
  std::unordered_map<uint64_t, Voxel> voxels_;
};

}  // namespace slam_mms::internal
