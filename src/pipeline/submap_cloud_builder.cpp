#include "pipeline/submap_cloud_builder.hpp"

#include <utility>

namespace slam_mms::internal {

SubmapCloudBuilder::SubmapCloudBuilder(double map_voxel_m, double registration_voxel_m,
                                       bool asynchronous)
    : map_(map_voxel_m, /*track_first_observation=*/true),
      registration_(registration_voxel_m),
      async_(asynchronous) {
  if (async_) worker_ = std::thread([this] { WorkerLoop(); });
}

SubmapCloudBuilder::~SubmapCloudBuilder() {
  if (!async_) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  work_cv_.notify_one();
  worker_.join();
}

void SubmapCloudBuilder::Accumulate(const Job& job) {
  const ScanStamp stamp{job.scan_start_ns, &job.dt, job.scan_index};
  map_.Add(job.cloud, job.T_submap_lidar, job.max_range_m, &stamp);
  registration_.Add(job.cloud, job.T_submap_lidar, job.max_range_m);
}

void SubmapCloudBuilder::Add(const PointCloud& cloud,
                             const std::vector<float>& dt_from_scan_start_s, int64_t scan_start_ns,
                             int64_t scan_index, const Eigen::Isometry3d& T_submap_lidar,
                             double max_range_m) {
  if (!async_) {
    // No copy: the stamp points at the caller's offsets for the duration of the call.
    const ScanStamp stamp{scan_start_ns, &dt_from_scan_start_s, scan_index};
    map_.Add(cloud, T_submap_lidar, max_range_m, &stamp);
    registration_.Add(cloud, T_submap_lidar, max_range_m);
    return;
  }
  uint64_t j = 0;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    // The slot of job j was last used by job j - kSlots: wait until that one is done.
    done_cv_.wait(lock, [this] { return submitted_ - done_ < kSlots; });
    j = submitted_;
  }
  Job& job = jobs_[j % kSlots];  // not touched by the worker until submitted_ > j
  job.cloud = cloud;             // copy-assignments reuse the slot's capacity
  job.dt = dt_from_scan_start_s;
  job.scan_start_ns = scan_start_ns;
  job.scan_index = scan_index;
  job.T_submap_lidar = T_submap_lidar;
  job.max_range_m = max_range_m;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++submitted_;
  }
  work_cv_.notify_one();
}

void SubmapCloudBuilder::Wait() {
  if (!async_) return;
  std::unique_lock<std::mutex> lock(mutex_);
  done_cv_.wait(lock, [this] { return done_ == submitted_; });
}

SubmapCloudBuilder::Clouds SubmapCloudBuilder::Build() {
  Wait();
  Clouds out;
  if (!async_) {
    out.map = map_.Cloud(&out.time_ns, &out.scan_index);
    out.registration = registration_.Cloud();
    return out;
  }
  // The two sorts are independent: the registration cloud on a second thread.
  std::thread registration([&] { out.registration = registration_.Cloud(); });
  out.map = map_.Cloud(&out.time_ns, &out.scan_index);
  registration.join();
  return out;
}

void SubmapCloudBuilder::Clear() {
  Wait();
  // The next submap needs about as many voxels: the tables are kept (see VoxelAccumulator::Reset).
  map_.Reset();
  registration_.Reset();
}

void SubmapCloudBuilder::WorkerLoop() {
  for (;;) {
    uint64_t j = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_cv_.wait(lock, [this] { return stop_ || done_ < submitted_; });
      if (done_ == submitted_) return;  // stop_ with nothing pending
      j = done_;
    }
    Accumulate(jobs_[j % kSlots]);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++done_;
    }
    done_cv_.notify_all();
  }
}

}  // namespace slam_mms::internal
