#pragma once
// The synthetic drive of the Localizer tests (localizer_test.cpp, localizer_submap_test.cpp): the
// street of tests/registration/synthetic_scene.hpp driven on a circular arc, its scans (simulated
// once per process), motion inputs, a Localizer on it, and tracking errors.
//
// Kept quick: 32 x 512 range images (as tests/surfel/surfel_map_submap_test.cpp) and one set of
// scans per process, shared by the tests (ray casting the scene costs more than level 1 itself).
// The body drives a circular arc (5 m/s, 3 deg/s yaw: a constant body twist, so a constant-
// velocity prediction and a constant-twist de-skew are exact), the LiDAR mounted 1.2 m above the
// body and slightly rotated, with 1 cm range noise.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "registration/synthetic_scene.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/pipeline/localizer.hpp"
#include "slam_mms/surfel/range_projection.hpp"

namespace slam_mms::testing {

inline constexpr int64_t kT0Ns = 1'317'000'000'000'000'000;  // 2011-09-26, a KITTI-like epoch
inline constexpr int64_t kScanPeriodNs = 100'000'000;        // 10 Hz
inline constexpr double kScanPeriodS = 0.1;
inline constexpr double kSweepS = 0.1;  // firing span of a skewed scan
inline constexpr double kNoiseM = 0.01;
// Every 4th scan starts a submap: 0.4 s >= WT = 0.35 s > 0.3 s (no rounding edge at WT).
inline constexpr double kWt = 0.35;
inline constexpr int kScansPerSubmap = 4;

// Tracking tolerances (all the tracking tests): 5 cm over the 5-12 m driven is <= 1 %, the
// LiDAR-only relative-error target of tests/pipeline/mapping_system_test.cpp, and 1.7x or more the
// largest error measured in these runs (2.9 cm, noisy POS; 1.2-2.2 cm otherwise); 0.2 deg is 3x the
// largest rotation error measured (0.068 deg, exact POS). The scans are deterministic (fixed
// seeds); the margins are for other compilers, libraries and the EGL renderer (kAuto). The drive
// yaws 7 deg and moves 12 m: a Localizer that does not track misses by far more.
inline constexpr double kTolTransM = 0.05;
inline constexpr double kTolRotDeg = 0.2;

inline Eigen::Isometry3d BodyLidar() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translate(Eigen::Vector3d(0.3, -0.1, 1.2));
  T.rotate(Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitZ()));
  T.rotate(Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitY()));
  return T;
}

/// The body twist [omega; v] in the body frame: 3 deg/s of yaw at 5 m/s forward.
inline Vector6d BodyTwist() {
  Vector6d xi;
  xi << 0.0, 0.0, 3.0 * M_PI / 180.0, 5.0, 0.0, 0.0;
  return xi;
}

/// The true body pose at t seconds after the first scan (the LiDAR at z = 0, 1.7 m above the
/// street of MakeStreetScene, starting 6 m before its centre).
inline Eigen::Isometry3d TrueBody(double t) {
  Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity();
  T0.translate(Eigen::Vector3d(-6.0, 0.5, -1.2));
  T0.rotate(Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitZ()));
  return T0 * se3::Exp(t * BodyTwist());
}
inline Eigen::Isometry3d TrueScanPose(int k) { return TrueBody(k * kScanPeriodS); }
inline Eigen::Vector3d TrueVelocityWorld(double t) {
  return TrueBody(t).linear() * BodyTwist().tail<3>();
}

inline Timestamp ScanStart(int k) { return Timestamp::FromNanoseconds(kT0Ns + k * kScanPeriodNs); }

inline RangeProjectionOptions SmallProjection() {
  RangeProjectionOptions p;
  p.rows = 32;
  p.cols = 512;
  return p;
}

inline Localizer::Options SmallOptions(MappingMode mode) {
  Localizer::Options o;
  o.mode = mode;
  o.submap_duration_s = kWt;
  o.surfels.renderer.projection = SmallProjection();
  return o;
}

inline double TransErrM(const Eigen::Isometry3d& truth, const Eigen::Isometry3d& est) {
  return (truth.inverse() * est).translation().norm();
}
inline double RotErrDeg(const Eigen::Isometry3d& truth, const Eigen::Isometry3d& est) {
  return RotationAngle((truth.inverse() * est).linear()) * 180.0 / M_PI;
}

/// A skewed scan: column c fired at (c + 0.5) / cols * kSweepS after the scan start, from the
/// LiDAR pose of that time (the ray casting of testing::SimulateScan, one pose per column), on the
/// body trajectory `body` (T_world_body at t seconds after the first scan; default TrueBody).
inline PointCloud SimulateSkewedScan(
    const testing::Scene& scene, const RangeProjection& proj, int k, uint32_t seed,
    const std::function<Eigen::Isometry3d(double)>& body = TrueBody) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(0.02f, 0.98f);
  std::normal_distribution<double> noise(0.0, kNoiseM);
  PointCloud cloud;
  for (int col = 0; col < proj.cols(); ++col) {
    const double dt = (col + 0.5) / proj.cols() * kSweepS;
    const Eigen::Isometry3d T = body(k * kScanPeriodS + dt) * BodyLidar();
    for (int row = 0; row < proj.rows(); ++row) {
      const Eigen::Vector3d d = proj.Unproject(static_cast<float>(col) + jitter(rng),
                                               static_cast<float>(row) + jitter(rng), 1.0f)
                                    .normalized()
                                    .cast<double>();
      Eigen::Vector3d n;
      const double t = scene.Cast(T.translation(), T.linear() * d, proj.options().max_range_m, &n);
      if (!std::isfinite(t)) continue;
      const double r = t + noise(rng);
      if (r < proj.options().min_range_m) continue;
      cloud.Add((r * d).cast<float>(), 0.0f, static_cast<float>(dt));
    }
  }
  return cloud;
}

/// Scan k of the drive: instantaneous (every point from the scan-start pose, time offsets 0) or
/// skewed over kSweepS. Simulated once per process.
inline const Scan& DriveScan(int k, bool skewed) {
  static std::map<std::pair<int, bool>, Scan> cache;
  auto it = cache.find({k, skewed});
  if (it != cache.end()) return it->second;
  static const testing::Scene scene = testing::MakeStreetScene();
  static const RangeProjection proj = RangeProjection::Create(SmallProjection()).value();
  Scan scan;
  scan.index = k;
  scan.stamp_start = ScanStart(k);
  scan.stamp_end =
      Timestamp::FromNanoseconds(scan.stamp_start.nanoseconds() + (skewed ? kScanPeriodNs : 0));
  scan.source = "synthetic_" + std::to_string(k);
  const uint32_t seed = 1000u + static_cast<uint32_t>(k) + (skewed ? 500u : 0u);
  scan.cloud =
      skewed ? SimulateSkewedScan(scene, proj, k, seed)
             : testing::SimulateScan(scene, proj, TrueScanPose(k) * BodyLidar(), kNoiseM, seed);
  return cache.emplace(std::make_pair(k, skewed), std::move(scan)).first->second;
}

inline ScanMotionInput ConstantVelocity() {
  ScanMotionInput m;
  m.type = MotionFactorType::kConstantVelocity;
  return m;
}

/// POS motion for scan k from POS poses at the scan's start and end (pos(k) is the pose at the
/// start of scan k; a scan ends where the next one starts).
template <typename PosFn>
ScanMotionInput Odometry(int k, const PosFn& pos) {
  ScanMotionInput m;
  m.type = MotionFactorType::kOdometry;
  m.T_world_body_pos_start = pos(k);
  m.T_world_body_pos_end = pos(k + 1);
  m.v_world_pos = TrueVelocityWorld(k * kScanPeriodS);
  return m;
}

inline std::unique_ptr<Localizer> MakeLocalizer(const Localizer::Options& o) {
  auto loc = Localizer::Create(o, BodyLidar());
  EXPECT_TRUE(loc.ok()) << loc.status().ToString();
  if (!loc.ok()) return nullptr;
  (*loc)->SetInitialPose(TrueScanPose(0));
  return std::move(loc).value();
}

/// Runs scans [first, last) with constant-velocity motion; the results in scan order.
inline std::vector<LocalizationResult> RunLidarOnly(Localizer* loc, int first, int last,
                                                    bool skewed = false) {
  std::vector<LocalizationResult> out;
  for (int k = first; k < last; ++k) {
    auto r = loc->ProcessScan(DriveScan(k, skewed), ConstantVelocity());
    EXPECT_TRUE(r.ok()) << "scan " << k << ": " << r.status().ToString();
    if (!r.ok()) break;
    out.push_back(*r);
  }
  return out;
}

struct TrackingError {
  double max_trans_m = 0.0, max_rot_deg = 0.0, rms_trans_m = 0.0;
};
/// Errors of the poses relative to pose `ref`: (est[ref]^-1 est[k]) against (true[ref]^-1 true[k]).
inline TrackingError RelativeError(const std::vector<Eigen::Isometry3d>& est,
                                   const std::vector<Eigen::Isometry3d>& truth, size_t ref = 0) {
  TrackingError e;
  double sum = 0.0;
  for (size_t k = ref; k < est.size(); ++k) {
    const Eigen::Isometry3d T_est = est[ref].inverse() * est[k];
    const Eigen::Isometry3d T_true = truth[ref].inverse() * truth[k];
    const double et = TransErrM(T_true, T_est);
    e.max_trans_m = std::max(e.max_trans_m, et);
    e.max_rot_deg = std::max(e.max_rot_deg, RotErrDeg(T_true, T_est));
    sum += et * et;
  }
  e.rms_trans_m = std::sqrt(sum / static_cast<double>(est.size() - ref));
  return e;
}

/// Puts the errors into the test's XML report (--gtest_output=xml), to follow the margins.
inline void RecordErrors(const TrackingError& e) {
  ::testing::Test::RecordProperty("max_trans_mm", std::to_string(1000.0 * e.max_trans_m));
  ::testing::Test::RecordProperty("max_rot_mdeg", std::to_string(1000.0 * e.max_rot_deg));
  ::testing::Test::RecordProperty("rms_trans_mm", std::to_string(1000.0 * e.rms_trans_m));
}

inline std::vector<Eigen::Isometry3d> Poses(const std::vector<LocalizationResult>& results) {
  std::vector<Eigen::Isometry3d> poses;
  for (const LocalizationResult& r : results) poses.push_back(r.T_world_body);
  return poses;
}
inline std::vector<Eigen::Isometry3d> TruePoses(int first, int last) {
  std::vector<Eigen::Isometry3d> poses;
  for (int k = first; k < last; ++k) poses.push_back(TrueScanPose(k));
  return poses;
}

inline bool SameCloud(const PointCloud& a, const PointCloud& b) {
  return a.points() == b.points() && a.intensities() == b.intensities();
}

// ---- options and inputs -------------------------------------------------------------------------

}  // namespace slam_mms::testing
