#include "slam_mms/drive/icp_odometry.hpp"

#include <cmath>
#include <string>
#include <string_view>

#include "core/option_error.hpp"
#include "pipeline/scan_deskewer.hpp"
#include "registration/point_icp.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/voxel_downsample.hpp"

namespace slam_mms {

Status IcpOdometryOptions::Validate() const {
  constexpr std::string_view kOwner = "IcpOdometryOptions";
  const std::pair<const char*, double> positive[] = {{"source_voxel_m", source_voxel_m},
                                                     {"target_voxel_m", target_voxel_m},
                                                     {"max_correspondence_m", max_correspondence_m},
                                                     {"huber_delta_m", huber_delta_m}};
  for (const auto& [field, v] : positive) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      return internal::OptionError(kOwner, field, v, "must be finite and > 0");
    }
  }
  if (!(min_range_m >= 0.0) || !std::isfinite(min_range_m)) {
    return internal::OptionError(kOwner, "min_range_m", min_range_m, "must be finite and >= 0");
  }
  if (deskew_passes < 1 || deskew_passes > 10) {
    return internal::OptionError(kOwner, "deskew_passes", deskew_passes, "must be in [1, 10]");
  }
  if (max_iterations < 1 || max_iterations > 1000) {
    return internal::OptionError(kOwner, "max_iterations", max_iterations, "must be in [1, 1000]");
  }
  if (num_threads < 1 || num_threads > 64) {
    return internal::OptionError(kOwner, "num_threads", num_threads, "must be in [1, 64]");
  }
  if (!T_world_body_first.matrix().allFinite()) {
    return InvalidArgumentError("IcpOdometryOptions::T_world_body_first is not finite");
  }
  return OkStatus();
}

namespace {

// The scan's finite points beyond min_range (judged on the raw points), de-skewed to the scan start
// with the lidar motion T_start_end over the sweep (exact per-point interpolation).
StatusOr<PointCloud> Prepare(const ScanDeskewer& deskewer, const Scan& scan,
                             const Eigen::Isometry3d& T_start_end, double min_range_m) {
  PointCloud deskewed;
  SLAM_MMS_RETURN_IF_ERROR(
      deskewer.Deskew(scan, T_start_end, Eigen::Isometry3d::Identity(), &deskewed));
  PointCloud out;
  out.reserve(scan.cloud.size());
  const std::vector<Eigen::Vector3f>& raw = scan.cloud.points();
  for (size_t i = 0; i < raw.size(); ++i) {
    if (raw[i].allFinite() && raw[i].norm() >= min_range_m) out.Add(deskewed.points()[i]);
  }
  return out;
}

}  // namespace

StatusOr<IcpOdometryResult> RunIcpOdometry(const DriveReader& reader,
                                           const IcpOdometryOptions& options,
                                           const std::atomic<bool>* stop) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  PointIcp::Options io;
  io.max_correspondence_distance = options.max_correspondence_m;
  io.huber_delta = options.huber_delta_m;
  io.max_iterations = options.max_iterations;
  io.source_voxel_size = 0.0;  // reduced here
  io.num_threads = options.num_threads;
  SLAM_MMS_ASSIGN_OR_RETURN(PointIcp icp, PointIcp::Create(io));
  // Without a velocity yet (the second scan) the prediction can be a metre or more off: that
  // registration first takes a coarse pass with a wide association gate, against scan 0.
  PointIcp::Options coarse_options = io;
  coarse_options.max_correspondence_distance = 4.0 * options.max_correspondence_m;
  coarse_options.huber_delta = 4.0 * options.huber_delta_m;
  SLAM_MMS_ASSIGN_OR_RETURN(PointIcp coarse, PointIcp::Create(coarse_options));
  ScanDeskewer::Options deskew_options;
  deskew_options.num_knots = 0;  // exact
  deskew_options.num_threads = options.num_threads;
  SLAM_MMS_ASSIGN_OR_RETURN(const ScanDeskewer deskewer, ScanDeskewer::Create(deskew_options));

  const Eigen::Isometry3d T_body_lidar = reader.streams().T_body_lidar;
  const Eigen::Isometry3d T_lidar_body = T_body_lidar.inverse();
  IcpOdometryResult result;
  Eigen::Isometry3d T_world_lidar = options.T_world_body_first * T_body_lidar;
  Eigen::Isometry3d T_prev_curr = Eigen::Isometry3d::Identity();  // last relative motion
  double prev_dt_s = 0.0;                                         // between their starts
  Timestamp prev_start;
  bool have_prev = false;
  bool have_velocity = false;
  double rms_sum = 0.0;
  size_t rms_n = 0;
  for (size_t k = 0; k < reader.NumScans(); ++k) {
    if (stop != nullptr && stop->load()) break;
    StatusOr<Scan> scan = reader.ReadScan(k);
    if (!scan.ok()) return scan.status().WithContext("IcpOdometry: scan " + std::to_string(k));
    const double duration_s = scan->DurationSeconds();
    const double dt_s = have_prev ? scan->stamp_start.SecondsSince(prev_start) : 0.0;
    // Constant velocity: the motion to this scan's start, scaled from the last registration's.
    Eigen::Isometry3d T_rel = Eigen::Isometry3d::Identity();
    if (have_velocity && prev_dt_s > 0.0) {
      T_rel = se3::Exp(Vector6d(se3::Log(T_prev_curr) * (dt_s / prev_dt_s)));
    }
    // The motion over the sweep from a motion T over dt_s (constant velocity).
    auto sweep_motion = [&](const Eigen::Isometry3d& T) {
      if (!options.deskew || !(dt_s > 0.0)) return Eigen::Isometry3d(Eigen::Isometry3d::Identity());
      return se3::Exp(Vector6d(se3::Log(T) * (duration_s / dt_s)));
    };
    SLAM_MMS_ASSIGN_OR_RETURN(PointCloud prepared,
                              Prepare(deskewer, *scan, sweep_motion(T_rel), options.min_range_m));
    if (prepared.size() < 100) {
      return DataLossError("IcpOdometry: scan " + std::to_string(k) + " (" + scan->source +
                           ") has " + std::to_string(prepared.size()) +
                           " usable points; at least 100 are needed");
    }
    if (have_prev) {
      if (!have_velocity) {
        SLAM_MMS_ASSIGN_OR_RETURN(const PointCloud source,
                                  VoxelDownsample(prepared, options.source_voxel_m));
        StatusOr<RegistrationResult> c = coarse.Align(source.View(), T_rel);
        if (c.ok() && c->IsUsable()) T_rel = c->T_target_source;
      }
      // De-skew with the motion being estimated, register, repeat: de-skewing with the previous
      // scan's motion alone feeds its error back with a gain near -1 (the estimates oscillate
      // from scan to scan).
      bool usable = false;
      for (int pass = 0; pass < options.deskew_passes; ++pass) {
        if (pass > 0) {
          SLAM_MMS_ASSIGN_OR_RETURN(
              prepared, Prepare(deskewer, *scan, sweep_motion(T_rel), options.min_range_m));
        }
        SLAM_MMS_ASSIGN_OR_RETURN(const PointCloud source,
                                  VoxelDownsample(prepared, options.source_voxel_m));
        StatusOr<RegistrationResult> r = icp.Align(source.View(), T_rel);
        usable = r.ok() && r->IsUsable();
        if (!usable) break;
        const double change = se3::Log(T_rel.inverse() * r->T_target_source).norm();
        T_rel = r->T_target_source;
        if (pass + 1 == options.deskew_passes || change < 1e-4) {
          rms_sum += r->rms_residual_m;
          ++rms_n;
          break;
        }
      }
      if (!usable) ++result.scans_unusable;
      T_world_lidar = Orthonormalized(T_world_lidar * T_rel);
      prev_dt_s = dt_s;
      T_prev_curr = T_rel;
      have_velocity = true;
    }
    SLAM_MMS_RETURN_IF_ERROR(
        result.T_world_body.Add(scan->stamp_start, T_world_lidar * T_lidar_body)
            .WithContext("IcpOdometry: scan " + std::to_string(k)));
    SLAM_MMS_ASSIGN_OR_RETURN(const PointCloud target,
                              VoxelDownsample(prepared, options.target_voxel_m));
    SLAM_MMS_RETURN_IF_ERROR(
        icp.SetTarget(target.View())
            .WithContext("IcpOdometry: scan " + std::to_string(k) + " as target"));
    if (!have_prev) {
      SLAM_MMS_RETURN_IF_ERROR(coarse.SetTarget(target.View()));
    }
    prev_start = scan->stamp_start;
    have_prev = true;
  }
  result.mean_rms_residual_m = rms_n ? rms_sum / static_cast<double>(rms_n) : 0.0;
  return result;
}

}  // namespace slam_mms
