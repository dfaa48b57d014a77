// Hdl64Lidar on a known plane, its timing convention, and de-skewing on the procedural city.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <unordered_map>

#include "slam_mms/sim/city_world.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms/sim/hdl64_lidar.hpp"

namespace slam_mms::sim {
namespace {

ReferenceTrajectory StaticTrajectory(const Eigen::Vector3d& p, double yaw) {
  std::vector<PoseSample> s;
  for (int k = 0; k < 30; ++k) s.push_back({0.1 * k, p, Eigen::Vector3d(0, 0, yaw)});
  auto t = ReferenceTrajectory::Fit(Timestamp::FromSeconds(1e9), s, {});
  EXPECT_TRUE(t.ok());
  return *t;
}

// A wall at x = 20 (facing -x) and a ground plane at z = -1.73.
CityWorld PlaneWorld() {
  TriangleMesh m;
  m.AddTriangle({20, -500, -100}, {20, 500, -100}, {20, 0, 500}, SurfaceClass::kBuilding, 0.5f);
  m.AddTriangle({-500, -500, -1.73f}, {500, -500, -1.73f}, {0, 500, -1.73f}, SurfaceClass::kRoad,
                0.2f);
  auto w = CityWorld::FromMesh(std::move(m));
  EXPECT_TRUE(w.ok());
  return std::move(*w);
}

TEST(Hdl64LidarTest, RangesToAKnownPlaneAreRight) {
  const CityWorld world = PlaneWorld();
  const ReferenceTrajectory traj = StaticTrajectory(Eigen::Vector3d::Zero(), 0.0);
  Hdl64Lidar::Options o;
  o.range_noise_sigma_m = 0.0;
  const Hdl64Lidar lidar(o);
  const auto out = lidar.Simulate(world, traj, Eigen::Isometry3d::Identity(), 0.5, 0, 1, 2);
  ASSERT_GT(out.scan.cloud.size(), 50000u);
  int wall = 0, ground = 0;
  for (size_t i = 0; i < out.scan.cloud.size(); ++i) {
    const Eigen::Vector3f p = out.scan.cloud.points()[i];
    if (out.surfaces[i] == SurfaceClass::kBuilding) {
      EXPECT_NEAR(p.x(), 20.0, 2e-3);
      ++wall;
    } else {
      EXPECT_NEAR(p.z(), -1.73, 2e-3);
      ++ground;
    }
  }
  EXPECT_GT(wall, 5000);
  EXPECT_GT(ground, 20000);
  // With 2 cm noise, range errors have sigma 2 cm and zero mean.
  Hdl64Lidar::Options on;
  const auto noisy =
      Hdl64Lidar(on).Simulate(world, traj, Eigen::Isometry3d::Identity(), 0.5, 0, 1, 2);
  double sum = 0, sum2 = 0;
  int n = 0;
  for (size_t i = 0; i < noisy.scan.cloud.size(); ++i) {
    if (noisy.surfaces[i] != SurfaceClass::kBuilding) continue;
    const Eigen::Vector3d p = noisy.scan.cloud.points()[i].cast<double>();
    const double r = p.norm();
    const double r_true = 20.0 / (p.x() / r);
    sum += r - r_true;
    sum2 += (r - r_true) * (r - r_true);
    ++n;
  }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.002);
  EXPECT_NEAR(sd, 0.02, 0.002);
}

TEST(Hdl64LidarTest, ClockwiseFromTheRearWithKittiTimeConvention) {
  const CityWorld world = PlaneWorld();
  const ReferenceTrajectory traj = StaticTrajectory(Eigen::Vector3d::Zero(), 0.3);
  const Hdl64Lidar lidar;
  const auto out = lidar.Simulate(world, traj, Eigen::Isometry3d::Identity(), 0.5, 3, 1, 2);
  const double period = lidar.PeriodSeconds();
  EXPECT_NEAR(out.scan.DurationSeconds(), lidar.LastFiringOffsetSeconds(), 1e-9);
  EXPECT_NEAR(out.scan.stamp_trigger.SecondsSince(out.scan.stamp_start), period / 2, 1e-9);
  double max_dev = 0.0;
  for (size_t i = 0; i < out.scan.cloud.size(); ++i) {
    const Eigen::Vector3f p = out.scan.cloud.points()[i];
    const double t_kitti = 0.5 * (-std::atan2(p.y(), p.x()) / M_PI + 1.0) * period;
    max_dev = std::max(max_dev, std::abs(t_kitti - out.scan.cloud.time_offsets_s()[i]));
  }
  EXPECT_LT(max_dev, 1.5 * period / 2083);
}

TEST(Hdl64LidarTest, ElevationBiasLowersThePoints) {
  const CityWorld world = PlaneWorld();
  const ReferenceTrajectory traj = StaticTrajectory(Eigen::Vector3d::Zero(), 0.0);
  Hdl64Lidar::Options o;
  o.range_noise_sigma_m = 0.0;
  o.elevation_bias_deg = 0.205;
  const auto out = Hdl64Lidar(o).Simulate(world, traj, Eigen::Isometry3d::Identity(), 0.5, 0, 1, 1);
  int n = 0;
  for (size_t i = 0; i < out.scan.cloud.size(); ++i) {
    if (out.surfaces[i] != SurfaceClass::kRoad) continue;
    const Eigen::Vector3f p = out.scan.cloud.points()[i];
    if (p.head<2>().norm() > 10.0) continue;
    EXPECT_LT(p.z(), -1.73 - 1e-3);  // written too low
    ++n;
  }
  EXPECT_GT(n, 1000);
}

// Point-to-plane distance of q to the reference cloud (PCA of the neighbours within 0.4 m).
class PlaneOracle {
 public:
  explicit PlaneOracle(const std::vector<Eigen::Vector3f>& pts) : pts_(pts) {
    for (size_t i = 0; i < pts.size(); ++i) grid_[Key(Cell(pts[i]))].push_back(static_cast<int>(i));
  }
  // 1 m where no surface is within 0.4 m; < 0 where the neighbourhood is not planar.
  double Distance(const Eigen::Vector3f& q) const {
    std::vector<Eigen::Vector3d> nb;
    const Eigen::Vector3i c = Cell(q);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = grid_.find(Key(Eigen::Vector3i(c + Eigen::Vector3i(dx, dy, dz))));
          if (it == grid_.end()) continue;
          for (int i : it->second)
            if ((pts_[i] - q).norm() < 0.4f) nb.push_back(pts_[i].cast<double>());
        }
    if (nb.size() < 8) return 1.0;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : nb) mean += p;
    mean /= nb.size();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : nb) cov += (p - mean) * (p - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    if (es.eigenvalues()(0) > 0.05 * es.eigenvalues()(1)) return -1.0;  // not planar
    return std::abs(es.eigenvectors().col(0).dot(q.cast<double>() - mean));
  }

 private:
  static Eigen::Vector3i Cell(const Eigen::Vector3f& p) {
    return (p / 0.4f).array().floor().cast<int>();
  }
  static int64_t Key(const Eigen::Vector3i& c) {
    return (static_cast<int64_t>(c.x() & 0x1FFFFF) << 42) |
           (static_cast<int64_t>(c.y() & 0x1FFFFF) << 21) | (c.z() & 0x1FFFFF);
  }
  const std::vector<Eigen::Vector3f>& pts_;
  std::unordered_map<int64_t, std::vector<int>> grid_;
};

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(Hdl64LidarTest, DeskewedScanLiesOnTheSceneWhileTheRawScanDoesNot) {
  DriveSimulator::Options o;
  o.seed = 3;
  // Start 0.7 s before the fastest turn of the first corner.
  auto route = ReferenceTrajectory::Fit(Timestamp(), DefaultUrbanRouteSamples(), o.fit);
  ASSERT_TRUE(route.ok());
  double t_turn = 0.0, best = 0.0;
  for (double t = 10.0; t < 60.0; t += 0.05) {
    const double w = std::abs(route->Evaluate(t).omega_body_radps.z());
    if (w > best) best = w, t_turn = t;
  }
  o.lead_in_s = t_turn - route->start_s() - 0.7;
  o.duration_s = 1.5;
  auto sim = DriveSimulator::Create(o);
  ASSERT_TRUE(sim.ok()) << sim.status().ToString();
  const auto& traj = sim->trajectory();
  const Eigen::Isometry3d T_body_lidar = o.T_lidar_body.inverse();
  const Hdl64Lidar lidar(o.lidar);
  // Reference surface samples from other scans (noise-free hits), the test scan in the middle.
  const double t_scan = sim->first_scan_s() + 0.7;
  EXPECT_GT(std::abs(traj.Evaluate(t_scan).omega_body_radps.z()), 0.2) << "must be turning";
  std::vector<Eigen::Vector3f> ref;
  for (double dt : {-0.6, -0.4, -0.2, 0.2, 0.4, 0.6}) {
    const auto o_ref = lidar.Simulate(sim->world(), traj, T_body_lidar, t_scan + dt, 100, 9, 2);
    ref.insert(ref.end(), o_ref.p_world_exact.begin(), o_ref.p_world_exact.end());
  }
  const PlaneOracle oracle(ref);
  const auto out = lidar.Simulate(sim->world(), traj, T_body_lidar, t_scan, 7, 9, 2);
  // De-skew as a consumer would: time from azimuth (KITTI convention) over [start, end].
  const double span = out.scan.DurationSeconds();
  std::vector<double> d_deskewed, d_raw;
  const Eigen::Isometry3d T_start = traj.Pose(t_scan) * T_body_lidar;
  for (size_t i = 0; i < out.scan.cloud.size(); i += 7) {
    const Eigen::Vector3f p = out.scan.cloud.points()[i];
    const double range = p.norm();
    if (range < 4.0 || range > 30.0 || out.surfaces[i] != SurfaceClass::kBuilding) continue;
    const double frac = 0.5 * (-std::atan2(p.y(), p.x()) / M_PI + 1.0);
    if (frac < 0.5) continue;  // the second half of the scan, where the skew is largest
    const Eigen::Isometry3d T_t = traj.Pose(t_scan + frac * span) * T_body_lidar;
    const double dd = oracle.Distance((T_t * p.cast<double>()).cast<float>());
    const double dr = oracle.Distance((T_start * p.cast<double>()).cast<float>());
    if (dd >= 0) d_deskewed.push_back(dd);
    if (dr >= 0) d_raw.push_back(dr);
  }
  ASSERT_GT(d_deskewed.size(), 300u);
  ASSERT_GT(d_raw.size(), 100u);
  const double med_deskewed = Median(d_deskewed), med_raw = Median(d_raw);
  RecordProperty("median_deskewed_m", std::to_string(med_deskewed));
  RecordProperty("median_raw_m", std::to_string(med_raw));
  EXPECT_LT(med_deskewed, 0.03);
  EXPECT_GT(med_raw, 0.10);
}

}  // namespace
}  // namespace slam_mms::sim
