#pragma once
// VoxelAccumulator: an incremental voxel grid (centroid and mean intensity per voxel), used to
// build the map clouds scan by scan without keeping the scans. Private to the pipeline.
// Optionally (track_first_observation) each voxel also keeps when and in which scan its first
// point was observed: the absolute time of that point (scan start + the point's own offset) and
// the scan's index, so map outputs can carry per-point GPS time and a point source ID (LAS). This
// costs one push_back per new voxel; the centroids are unchanged. Cells are internal::VoxelGrid's
// (exact floor(p / voxel), keyed by the full cell: no wrap far from the origin); points whose cell
// is out of the grid's range (beyond 2^30 - 1 voxels) are dropped and counted.

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/voxel_grid.hpp"
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
      : grid_(voxel_m), track_(track_first_observation) {}

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
  /// Points (finite, within range) dropped because their cell is beyond the grid's range.
  size_t num_out_of_range() const { return out_of_range_; }
  size_t MemoryBytes() const {
    return table_.capacity() * sizeof(Entry) + order_.capacity() * sizeof(uint32_t);
  }
  /// Empties the grid and keeps its memory (the table's size, the stamp capacity) for the next
  /// run of Adds: a submap after a submap then fills a table of the size the last one needed
  /// instead of growing one by doubling from fresh pages (page faults were ~30 % of the pipeline's
  /// faults). The clouds are the same either way (they are sorted by cell, and each voxel sums
  /// its points in Add order).
  void Reset();

 private:
  /// One slot of an open-addressing table (linear probing, power-of-two size, load <= 1/2, slot
  /// from the top bits of HashVoxelCell): cell and sums share a cache line (32 bytes, aligned to
  /// 32: an entry never straddles two), and Add prefetches the slots of a batch of points before
  /// it touches them (a std::unordered_map node per voxel made this 13 % of LiDAR-only CPU time).
  /// Positions are summed as float offsets from the voxel's corner (exact enough: < voxel size).
  struct alignas(32) Entry {
    VoxelCell cell;
    float dx = 0, dy = 0, dz = 0;
    float intensity = 0;
    uint32_t count = 0;  ///< 0: an empty slot (Find returns a new entry only to add a point).
  };
  static_assert(sizeof(Entry) == 32, "one entry per half cache line");
  void Reserve(size_t voxels);
  Entry& Find(const VoxelCell& cell, size_t slot);
  VoxelGrid grid_;
  bool track_ = false;
  size_t out_of_range_ = 0;
  std::vector<int64_t> first_time_ns_;  ///< By creation order, when tracking.
  std::vector<int64_t> first_scan_;
  std::vector<Entry> table_;
  std::vector<uint32_t>
      order_;  ///< Per slot of table_ (when tracking): the entry's creation index.
  size_t size_ = 0;
};

}  // namespace slam_mms::internal
