#pragma once
// SubmapCloudBuilder: the current submap's two clouds (the final map at map_voxel_m with
// per-voxel first-observation stamps, and the registration cloud at registration_voxel_m), built
// scan by scan from the de-skewed scans. Private to the pipeline.
//
// Accumulating a scan touches every point twice (two voxel hashes); nothing in level 1 reads the
// result before the submap is closed, so with `asynchronous` the scans are accumulated on one
// background thread, in submission order, while level 1 goes on with the next scan. The clouds are
// the same bits either way (the same Add calls in the same order); Close/Clear wait for the
// scans submitted before them. A submitted scan is copied into one of a few reused buffers, so
// the caller's cloud may change right after Add returns and no scan allocates once warm.

#include <Eigen/Geometry>
#include <array>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#include "pipeline/voxel_accumulator.hpp"
#include "slam_mms/core/point_cloud.hpp"

namespace slam_mms::internal {

class SubmapCloudBuilder {
 public:
  struct Clouds {
    PointCloud map;                   ///< Centroids at map_voxel_m (submap frame).
    std::vector<int64_t> time_ns;     ///< Per map point: time of the voxel's first point.
    std::vector<int64_t> scan_index;  ///< Per map point: index of that point's scan.
    PointCloud registration;          ///< Centroids at registration_voxel_m.
  };

  SubmapCloudBuilder(double map_voxel_m, double registration_voxel_m, bool asynchronous);
  ~SubmapCloudBuilder();
  SubmapCloudBuilder(const SubmapCloudBuilder&) = delete;
  SubmapCloudBuilder& operator=(const SubmapCloudBuilder&) = delete;

  /// Adds `cloud` (LiDAR frame, index-aligned with `dt_from_scan_start_s` when that has its size)
  /// at T_submap_lidar, the points within max_range_m.
  void Add(const PointCloud& cloud, const std::vector<float>& dt_from_scan_start_s,
           int64_t scan_start_ns, int64_t scan_index, const Eigen::Isometry3d& T_submap_lidar,
           double max_range_m);
  /// The clouds of everything added since the last Clear (waits for pending scans).
  Clouds Build();
  /// Empties both grids (waits for pending scans); their tables are kept for the next submap.
  void Clear();

 private:
  struct Job {
    PointCloud cloud;
    std::vector<float> dt;
    int64_t scan_start_ns = 0;
    int64_t scan_index = 0;
    Eigen::Isometry3d T_submap_lidar = Eigen::Isometry3d::Identity();
    double max_range_m = 0.0;
  };
  static constexpr size_t kSlots = 3;  ///< Scans in flight at most (the caller waits beyond).

  void Accumulate(const Job& job);
  void Wait();
  void WorkerLoop();

  VoxelAccumulator map_;
  VoxelAccumulator registration_;
  bool async_;
  std::array<Job, kSlots> jobs_;
  // Jobs [done_, submitted_) are pending; job j lives in jobs_[j % kSlots].
  uint64_t submitted_ = 0;
  uint64_t done_ = 0;
  bool stop_ = false;
  std::mutex mutex_;
  std::condition_variable work_cv_;
  std::condition_variable done_cv_;
  std::thread worker_;
};

}  // namespace slam_mms::internal
