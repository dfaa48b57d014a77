#pragma once
// ScanDeskewer: the de-skew stage of level 1 (paper §5.1.2). Every point of a raw scan, recorded at
// its own time stamp_start + dt, is moved to the scan's reference time (the first point's time,
// stamp_start) with the relative body motion over the scan, assuming uniform motion (constant
// linear and angular velocity) between stamp_start and stamp_end:
//
//   T_bstart_b(dt) = Exp-interpolation of T_bstart_bend at alpha = dt / duration
//   p_lidar_start  = T_lidar_body * T_bstart_b(dt) * T_body_lidar * p_lidar(dt)
//
// The motion prior T_bstart_bend comes from the InsFilter while GNSS is good, from IMU
// preintegration during outages, or from constant velocity in LiDAR-only mode (the Localizer
// picks).
//
// Thread safety: stateless apart from options; Deskew may run concurrently on distinct outputs.
// Work is split over Options::num_threads threads (the caller's included).

#include <Eigen/Geometry>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/deskew_options.hpp"

namespace slam_mms {

class ScanDeskewer {
 public:
  /// The SDK's options (DeskewOptions) plus the thread count its owner sets.
  struct Options : DeskewOptions {
    int num_threads = 2;  ///< Threads for the per-point loop (>= 1).
    [[nodiscard]] Status Validate() const;
  };

  ScanDeskewer();
  static StatusOr<ScanDeskewer> Create(const Options& options);

  /// De-skews `scan` (points in the lidar frame, time_offsets_s from stamp_start) into `out`
  /// (lidar frame at stamp_start; intensities copied, time offsets set to 0). `T_bstart_bend` is
  /// the body motion from stamp_start to stamp_end. A scan of zero duration is copied unchanged.
  /// InvalidArgument for a non-finite motion or a time offset outside [-1 ms, duration + 1 ms]
  /// (naming the scan's source and the point).
  Status Deskew(const Scan& scan, const Eigen::Isometry3d& T_bstart_bend,
                const Eigen::Isometry3d& T_body_lidar, PointCloud* out) const;

  /// The time-offset check of Deskew on its own (InvalidArgument naming the scan and the first
  /// point outside [-1 ms, duration + 1 ms]), for a caller that must know before it changes any
  /// state.
  static Status CheckTimeOffsets(const Scan& scan);

  const Options& options() const { return options_; }

 private:
  explicit ScanDeskewer(const Options& options) : options_(options) {}
  Options options_;
};

}  // namespace slam_mms
