#pragma once
// VoxelAccumulator: an incremental voxel grid (centroid and mean intensity per voxel), used to
// build the map clouds scan by scan without keeping the scans. Private to the pipeline.
// Optionally (track_first_observation) each voxel also keeps when and in which scan its first
// point was observed: the absolute time of that point (scan start + the point's own offset) and
// the scan's index, so map outputs can carry per-point GPS time and a point source ID (LAS). This
// costs one push_back per new voxel; the centroids are unchanged.

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"

namespace slam_mms::internal {

/// Where the points given to VoxelAccumulator::Add come from.
struct ScanStamp {
  int64_t scan_start_ns = 0;  ///< Absolute time of the scan's first point.
  /// Per-point offsets from the scan start [s] (the raw scan's, index-aligned with the cloud
  /// added); null: all points at scan_start_ns.
  const std::vector<float>* dt_from_scan_start_s = nullptr;
  int64_t scan_index = 0;
};

class VoxelAccumulator {
 public:
  explicit VoxelAccumulator(double voxel_m = 0.1, bool track_first_observation = false)
      : voxel_(voxel_m), inv_voxel_(1.0 / voxel_m), track_(track_first_observation) {}

  /// Adds the points of `cloud` (frame c) transformed by T_frame_c, those within max_range_m of
  /// the cloud's origin. `stamp` (may be null) feeds the first-observation record.
  void Add(const PointCloud& cloud, const Eigen::Isometry3d& T_frame_c, double max_range_m,
           const ScanStamp* stamp = nullptr);
  /// The centroids (frame of the accumulator), sorted by voxel key (deterministic).
  PointCloud Cloud() const;
  /// The same, and per centroid the time [ns] and scan index of the voxel's first point (empty
  /// when not tracking).
  PointCloud Cloud(std::vector<int64_t>* first_time_ns, std::vector<int64_t>* first_scan) const;
  size_t size() const { return size_; }
  size_t MemoryBytes() const { return table_.capacity() * sizeof(Entry); }
  /// Empties the grid and gives its memory back.
  void Clear();

 private:
  /// One slot of an open-addressing table (linear probing, power-of-two size, load <= 1/2): key
  /// and sums share a cache line, and Add prefetches the slots of a batch of points before it
  /// touches them (a std::unordered_map node per voxel made this 13 % of LiDAR-only CPU time).
  /// Positions are summed as float offsets from the voxel's corner (exact enough: < voxel size).
  struct Entry {
    uint64_t key = kEmpty;
    float dx = 0, dy = 0, dz = 0;
    float intensity = 0;
    uint32_t count = 0;
    uint32_t order = 0;  ///< Creation index: into first_time_ns_ / first_scan_ (in the padding).
  };
  static constexpr uint64_t kEmpty = ~uint64_t{0};  ///< Keys use 63 bits, never all ones.
  void Reserve(size_t voxels);
  Entry& Find(uint64_t key, size_t slot);
  double voxel_;
  double inv_voxel_;
  bool track_ = false;
  std::vector<int64_t> first_time_ns_;  ///< By Entry::order, when tracking.
  std::vector<int64_t> first_scan_;
  std::vector<Entry> table_;
  size_t size_ = 0;
};

}  // namespace slam_mms::internal
