#include "pipeline/scan_deskewer.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "core/option_error.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {

Status DeskewOptions::Validate() const {
  if (num_knots < 0 || num_knots == 1) {
    return internal::OptionError("ScanDeskewer::Options", "num_knots", num_knots,
                                 "must be 0 (exact) or >= 2");
  }
  return OkStatus();
}

Status ScanDeskewer::Options::Validate() const {
  if (num_threads < 1) {
    return internal::OptionError("ScanDeskewer::Options", "num_threads", num_threads,
                                 "must be >= 1");
  }
  return DeskewOptions::Validate();
}

namespace {

// A point's time offset is within the scan (1 ms of slack for the stamps' rounding).
constexpr float kTimeTolerance = 1e-3f;
bool InScanTime(float dt, double duration) {
  return dt >= -kTimeTolerance && dt <= static_cast<float>(duration) + kTimeTolerance;
}

Status TimeOffsetError(const Scan& scan, size_t i) {
  return InvalidArgumentError(
      "ScanDeskewer: scan '" + scan.source + "' point " + std::to_string(i) + " has time offset " +
      std::to_string(scan.cloud.time_offsets_s()[i]) + " s outside the scan duration [0, " +
      std::to_string(scan.DurationSeconds()) + "] s");
}

}  // namespace

ScanDeskewer::ScanDeskewer() = default;

Status ScanDeskewer::CheckTimeOffsets(const Scan& scan) {
  const double duration = scan.DurationSeconds();
  if (!(duration > 0.0)) return OkStatus();  // Deskew copies such a scan unchanged
  const auto& offsets = scan.cloud.time_offsets_s();
  for (size_t i = 0; i < offsets.size(); ++i) {
    if (!InScanTime(offsets[i], duration)) return TimeOffsetError(scan, i);
  }
  return OkStatus();
}

StatusOr<ScanDeskewer> ScanDeskewer::Create(const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  return ScanDeskewer(options);
}

Status ScanDeskewer::Deskew(const Scan& scan, const Eigen::Isometry3d& T_bstart_bend,
                            const Eigen::Isometry3d& T_body_lidar, PointCloud* out) const {
  if (!T_bstart_bend.matrix().allFinite() || !T_body_lidar.matrix().allFinite()) {
    return InvalidArgumentError("ScanDeskewer: non-finite motion prior for scan '" + scan.source +
                                "'");
  }
  const PointCloud& in = scan.cloud;
  const size_t n = in.size();
  out->resize(n);
  const double duration = scan.DurationSeconds();
  if (n == 0) return OkStatus();
  if (!(duration > 0.0)) {
    out->points() = in.points();
    out->intensities() = in.intensities();
    std::fill(out->time_offsets_s().begin(), out->time_offsets_s().end(), 0.0f);
    return OkStatus();
  }

  // Motion of the lidar over the scan: T_lstart_lend = T_lidar_body T_bstart_bend T_body_lidar.
  const Eigen::Isometry3d T_lidar_body = T_body_lidar.inverse();
  const Eigen::Isometry3d T_lstart_lend = T_lidar_body * T_bstart_bend * T_body_lidar;
  const Vector6d xi = se3::Log(T_lstart_lend);  // constant twist over the scan

  // Knots of T_lstart_l(alpha), alpha in [0, 1] (float matrices for the hot loop).
  const int knots = options_.num_knots == 0 ? 0 : options_.num_knots;
  std::vector<Eigen::Matrix<float, 3, 4>> knot_T;
  if (knots > 0) {
    knot_T.resize(static_cast<size_t>(knots));
    for (int k = 0; k < knots; ++k) {
      const double alpha = static_cast<double>(k) / (knots - 1);
      knot_T[static_cast<size_t>(k)] = se3::Exp(alpha * xi).matrix().topRows<3>().cast<float>();
    }
  }

  const auto& offsets = in.time_offsets_s();
  std::vector<long> bad(static_cast<size_t>(options_.num_threads), -1);
  auto work = [&](int thread, size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const float dt = offsets[i];
      if (!InScanTime(dt, duration)) {
        if (bad[static_cast<size_t>(thread)] < 0)
          bad[static_cast<size_t>(thread)] = static_cast<long>(i);
        out->points()[i] = in.points()[i];
        continue;
      }
      const double alpha = std::clamp(static_cast<double>(dt) / duration, 0.0, 1.0);
      Eigen::Vector3f p;
      if (knots == 0) {
        p = (se3::Exp(alpha * xi) * in.points()[i].cast<double>()).cast<float>();
      } else {
        const double s = alpha * (knots - 1);
        const int k0 = std::min(static_cast<int>(s), knots - 2);
        const float w = static_cast<float>(s - k0);
        const Eigen::Vector4f ph(in.points()[i].x(), in.points()[i].y(), in.points()[i].z(), 1.0f);
        p = (1.0f - w) * (knot_T[static_cast<size_t>(k0)] * ph) +
            w * (knot_T[static_cast<size_t>(k0 + 1)] * ph);
      }
      out->points()[i] = p;
    }
  };
  const int threads = std::min<int>(options_.num_threads, static_cast<int>(n / 4096) + 1);
  std::vector<std::thread> pool;
  const size_t chunk = (n + threads - 1) / threads;
  for (int t = 1; t < threads; ++t) {
    pool.emplace_back(work, t, std::min(n, t * chunk), std::min(n, (t + 1) * chunk));
  }
  work(0, 0, std::min(n, chunk));
  for (auto& th : pool) th.join();
  out->intensities() = in.intensities();
  std::fill(out->time_offsets_s().begin(), out->time_offsets_s().end(), 0.0f);
  for (long b : bad) {
    if (b >= 0) return TimeOffsetError(scan, static_cast<size_t>(b));
  }
  return OkStatus();
}

}  // namespace slam_mms
