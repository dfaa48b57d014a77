// A small SDK consumer: runs the MappingSystem facade (mode kFull) of an installed slam_mms on a
// few synthetic frames and checks the result against the known truth. Exits 0 when every check
// passes. Uses only the standard library, Eigen and the SDK headers (pipeline facade, core types).
//
// Scene: a closed street box (ground z = 0, side walls y = +-7 m, end walls x = -15 m and +45 m)
// with a few pillars, so that registration is constrained along the travel direction too.
// Vehicle: drives along +x (ENU east) at 5 m/s; body x forward, y left, z up; LiDAR 1.7 m up.
// Sensors: an HDL-64-like LiDAR (each firing cast from the pose at its own time, so the scans are
// skewed like raw ones), a 100 Hz IMU and 10 Hz RTK-fixed GNSS, all noise-free (deterministic).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

#include "slam_mms/slam_mms.hpp"  // the SDK in one include

namespace {

using slam_mms::Timestamp;

constexpr double kPi = 3.14159265358979323846;
constexpr int kNumScans = 30;
constexpr double kScanPeriodS = 0.1;         // 10 Hz LiDAR and GNSS.
constexpr double kImuPeriodS = 0.01;         // 100 Hz IMU.
constexpr double kSpeedMps = 5.0;            // Along world +x.
constexpr int kNumBeams = 64;                // Uniform elevations from +2.0 down to -24.8 deg.
constexpr int kFiringsPerRevolution = 1024;  // = the default range-image width (64 x 1024).
constexpr double kLidarHeightM = 1.7;
constexpr double kMaxErrorM = 0.05;  // Position error tolerances (a working run: ~mm).
constexpr double kRmsErrorM = 0.03;
const slam_mms::GeodeticPoint kOrigin{49.0, 8.4, 110.0};
const Timestamp kT0 = Timestamp::FromNanoseconds(1'700'000'000'000'000'000);  // First scan start.

Timestamp At(double t_s) {
  return Timestamp::FromNanoseconds(kT0.nanoseconds() + std::llround(t_s * 1e9));
}

/// True body pose at t_s seconds after the first scan's start: constant velocity, level, east.
Eigen::Isometry3d TrueWorldBody(double t_s) {
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  T_world_body.translation() = Eigen::Vector3d(kSpeedMps * t_s, 0.0, 0.0);
  return T_world_body;
}

/// An axis-aligned box [lo, hi].
struct Box {
  Eigen::Vector3d lo, hi;
};
const Box kStreet{{-15.0, -7.0, 0.0}, {45.0, 7.0, 8.0}};  // Seen from inside; open at the top.
const std::vector<Box> kPillars = {
    {{-8.5, 4.0, 0.0}, {-7.5, 5.0, 4.0}},   {{3.6, 5.1, 0.0}, {4.4, 5.9, 5.0}},
    {{8.5, -6.0, 0.0}, {9.5, -4.0, 3.0}},   {{15.0, 4.4, 0.0}, {17.0, 5.6, 4.0}},
    {{21.6, -5.9, 0.0}, {22.4, -5.1, 6.0}}, {{29.2, 3.7, 0.0}, {30.8, 5.3, 2.5}},
    {{35.8, -5.0, 0.0}, {38.2, -4.0, 4.0}}};

/// Range along the unit ray o + t d to the first surface, or +inf (out through the open top).
double CastRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t_hit = std::numeric_limits<double>::infinity();
  int exit_axis = -1;
  for (int i = 0; i < 3; ++i) {  // Leaving the street box through its nearest far plane.
    if (d[i] == 0.0) continue;
    const double t = ((d[i] > 0.0 ? kStreet.hi[i] : kStreet.lo[i]) - o[i]) / d[i];
    if (t < t_hit) {
      t_hit = t;
      exit_axis = i;
    }
  }
  if (exit_axis == 2 && d.z() > 0.0) t_hit = std::numeric_limits<double>::infinity();
  for (const Box& box : kPillars) {  // Slab test; the sensor is never inside a pillar.
    double t_in = 0.0, t_out = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      const double a = (box.lo[i] - o[i]) / d[i], b = (box.hi[i] - o[i]) / d[i];
      t_in = std::max(t_in, std::min(a, b));
      t_out = std::min(t_out, std::max(a, b));
    }
    if (t_in <= t_out && t_in > 0.0) t_hit = std::min(t_hit, t_in);
  }
  return t_hit;
}

/// One revolution as the HDL-64 driver delivers it: firing j at azimuth pi - 2 pi j / N and time
/// offset j / (N * 10 Hz) (clockwise from behind, as KITTI), every point in the lidar frame of its
/// own firing time.
slam_mms::Scan SimulateScan(int k, const Eigen::Isometry3d& T_body_lidar) {
  slam_mms::Scan scan;
  scan.index = k;
  const double t_start_s = k * kScanPeriodS;
  const double dt_firing_s = kScanPeriodS / kFiringsPerRevolution;
  scan.stamp_start = At(t_start_s);
  scan.stamp_end = At(t_start_s + (kFiringsPerRevolution - 1) * dt_firing_s);
  scan.stamp_trigger = At(t_start_s + 0.5 * kScanPeriodS);
  scan.cloud.reserve(kNumBeams * kFiringsPerRevolution);
  for (int j = 0; j < kFiringsPerRevolution; ++j) {
    const double dt_s = j * dt_firing_s;
    const Eigen::Isometry3d T_world_lidar = TrueWorldBody(t_start_s + dt_s) * T_body_lidar;
    const double azimuth = kPi - 2.0 * kPi * j / kFiringsPerRevolution;
    for (int b = 0; b < kNumBeams; ++b) {
      const double elevation = (2.0 - 26.8 * b / (kNumBeams - 1)) * kPi / 180.0;
      const Eigen::Vector3d d_lidar(std::cos(elevation) * std::cos(azimuth),
                                    std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      const Eigen::Vector3d d_world = T_world_lidar.linear() * d_lidar;
      const double range_m = CastRay(T_world_lidar.translation(), d_world);
      if (!(range_m > 2.0 && range_m < 120.0)) continue;  // The HDL-64's range gate.
      const Eigen::Vector3d p_world = T_world_lidar.translation() + range_m * d_world;
      const Eigen::Vector3d p_lidar = T_world_lidar.inverse() * p_world;
      scan.cloud.Add(p_lidar.cast<float>(), 0.5f, static_cast<float>(dt_s));
    }
  }
  return scan;
}

/// WGS-84 fix of a world (ENU at kOrigin) position: small-offset approximation with the meridian
/// (M) and prime-vertical (N) radii of curvature at the origin, good to mm over tens of metres.
slam_mms::GnssFix FixAt(double t_s, const Eigen::Vector3d& p_world) {
  constexpr double kA = 6378137.0, kE2 = 6.69437999014e-3;  // WGS-84 semi-major axis, e^2.
  const double lat = kOrigin.latitude_deg * kPi / 180.0;
  const double w = 1.0 - kE2 * std::sin(lat) * std::sin(lat);
  const double radius_n = kA / std::sqrt(w), radius_m = kA * (1.0 - kE2) / (w * std::sqrt(w));
  slam_mms::GnssFix fix;
  fix.stamp = At(t_s);
  fix.latitude_deg =
      kOrigin.latitude_deg + p_world.y() / (radius_m + kOrigin.height_m) * 180.0 / kPi;
  fix.longitude_deg = kOrigin.longitude_deg +
                      p_world.x() / ((radius_n + kOrigin.height_m) * std::cos(lat)) * 180.0 / kPi;
  fix.height_m = kOrigin.height_m + p_world.z();
  fix.sigma_horizontal_m = 0.02;
  fix.sigma_vertical_m = 0.03;
  fix.type = slam_mms::GnssFixType::kRtkFixed;
  fix.num_satellites = 12;
  return fix;
}

int Fail(const char* what, const slam_mms::Status& status) {
  std::fprintf(stderr, "consumer: %s: %s\n", what, status.ToString().c_str());
  return 1;
}

}  // namespace

int main() {
  using slam_mms::MappingSystem;
  MappingSystem::Options options;
  options.mode = slam_mms::MappingMode::kFull;
  options.T_body_lidar.translation() = Eigen::Vector3d(0.0, 0.0, kLidarHeightM);
  options.origin = kOrigin;  // World = ENU at kOrigin, so the truth compares directly.
  // Default range images are 64 x 1024, HDL-64 from +3 to -25 deg: the synthetic scan fits them.
  auto created = MappingSystem::Create(options);
  if (!created.ok()) return Fail("Create", created.status());
  MappingSystem& system = **created;

  // IMU: constant velocity, level: the specific force is -g_world = (0, 0, +g) in body, gyro zero.
  // g is the filter's default model (Somigliana normal gravity at the origin).
  const double gravity_mps2 =
      slam_mms::InsFilter::NormalGravity(kOrigin.latitude_deg, kOrigin.height_m);
  // The streams run from the first scan's start to 0.2 s past the last scan. They do not start
  // earlier: level 2 attaches a fix up to 0.15 s before the first scan to the first scan's pose
  // (0.5 m off at 5 m/s), which shifts the final trajectory by ~0.18 m here.
  const double t_last_s = (kNumScans + 2) * kScanPeriodS;
  std::vector<slam_mms::ImuSample> imu;
  for (int i = 0; i * kImuPeriodS <= t_last_s + 1e-9; ++i) {
    slam_mms::ImuSample sample;
    sample.stamp = At(i * kImuPeriodS);
    sample.accel_mps2 = Eigen::Vector3d(0.0, 0.0, gravity_mps2);
    imu.push_back(sample);
  }
  std::vector<slam_mms::GnssFix> gnss;  // Antenna at the body origin (default lever arm zero).
  for (int i = 0; i * kScanPeriodS <= t_last_s + 1e-9; ++i) {
    const double t_s = i * kScanPeriodS;
    gnss.push_back(FixAt(t_s, TrueWorldBody(t_s).translation()));
  }

  // The filter starts aligned: true attitude and velocity at the first IMU/GNSS stamp.
  slam_mms::InsState init;
  init.stamp = At(0.0);
  init.T_world_body = TrueWorldBody(0.0);
  init.v_world_mps = Eigen::Vector3d(kSpeedMps, 0.0, 0.0);
  if (const slam_mms::Status s = system.InitializePos(init); !s.ok()) {
    return Fail("InitializePos", s);
  }

  // Feed in time order: all IMU/GNSS up to `until`, merged by stamp (a fix after the IMU sample
  // of the same stamp), then the scan, as a sensor delivers it at its end.
  size_t i_imu = 0, i_gnss = 0;
  auto feed_until = [&](Timestamp until) -> slam_mms::Status {
    while (true) {
      const bool imu_left = i_imu < imu.size() && imu[i_imu].stamp <= until;
      const bool gnss_left = i_gnss < gnss.size() && gnss[i_gnss].stamp <= until;
      if (!imu_left && !gnss_left) return slam_mms::OkStatus();
      if (imu_left && (!gnss_left || imu[i_imu].stamp <= gnss[i_gnss].stamp)) {
        SLAM_MMS_RETURN_IF_ERROR(system.AddImu(imu[i_imu++]));
      } else {
        SLAM_MMS_RETURN_IF_ERROR(system.AddGnss(gnss[i_gnss++]));
      }
    }
  };
  for (int k = 0; k < kNumScans; ++k) {
    const slam_mms::Scan scan = SimulateScan(k, options.T_body_lidar);
    if (const slam_mms::Status s = feed_until(scan.stamp_end); !s.ok()) return Fail("feed", s);
    if (const slam_mms::Status s = system.AddScan(scan); !s.ok()) return Fail("AddScan", s);
  }
  if (const slam_mms::Status s = feed_until(At(t_last_s + 1.0)); !s.ok()) return Fail("feed", s);
  if (const slam_mms::Status s = system.Finish(); !s.ok()) return Fail("Finish", s);

  // Checks.
  bool ok = true;
  auto check = [&ok](bool condition, const char* what) {
    if (!condition) std::fprintf(stderr, "consumer: check failed: %s\n", what);
    ok = ok && condition;
  };
  check(system.results().size() == static_cast<size_t>(kNumScans), "one result per scan");
  check(system.num_skipped_scans() == 0, "no skipped scans");
  const slam_mms::Trajectory trajectory = system.FinalTrajectory();
  check(trajectory.size() == static_cast<size_t>(kNumScans), "one final pose per scan");
  double max_error_m = 0.0, sum_sq_m2 = 0.0;
  for (size_t k = 0; k < trajectory.size(); ++k) {
    const double t_s = trajectory[k].stamp.SecondsSince(kT0);
    check(std::abs(t_s - static_cast<double>(k) * kScanPeriodS) < 1e-6,
          "final pose stamped at its scan's start");
    const double e =
        (trajectory[k].T_world_body.translation() - TrueWorldBody(t_s).translation()).norm();
    max_error_m = std::max(max_error_m, e);
    sum_sq_m2 += e * e;
  }
  const double rms_error_m =
      trajectory.empty() ? 0.0 : std::sqrt(sum_sq_m2 / static_cast<double>(trajectory.size()));
  check(max_error_m < kMaxErrorM, "max position error below tolerance");
  check(rms_error_m < kRmsErrorM, "rms position error below tolerance");
  const slam_mms::PointCloud map = system.FinalMap();
  check(!map.empty(), "final map not empty");
  const auto origin = system.Origin();
  if (!origin.ok()) return Fail("Origin", origin.status());
  check(std::abs(origin->latitude_deg - kOrigin.latitude_deg) < 1e-12 &&
            std::abs(origin->longitude_deg - kOrigin.longitude_deg) < 1e-12 &&
            std::abs(origin->height_m - kOrigin.height_m) < 1e-9,
        "origin as given");

  std::printf(
      "slam_mms %s: MappingSystem (%s) on %d synthetic scans: max position error %.3f m, rms "
      "%.3f m, map %zu points%s\n",
      SLAM_MMS_VERSION_STRING, slam_mms::MappingModeName(options.mode), kNumScans, max_error_m,
      rms_error_m, map.size(), ok ? "" : " (FAILED)");
  return ok ? 0 : 1;
}
