// The simulator's optional realism models (docs/simulator.md "Realism models"): per-laser
// calibration residuals, beam divergence (mixed pixels), volumetric vegetation, ground roughness.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>

#include "sim/random.hpp"  // the simulator's seed derivation (MixSeed(seed, 50) for the LiDAR)
#include "slam_mms/sim/city_world.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms/sim/hdl64_lidar.hpp"
#include "testing/test_data.hpp"

namespace slam_mms::sim {
namespace {

ReferenceTrajectory StaticTrajectory() {
  std::vector<PoseSample> s;
  for (int k = 0; k < 30; ++k)
    s.push_back({0.1 * k, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
  auto t = ReferenceTrajectory::Fit(Timestamp::FromSeconds(1e9), s, {});
  EXPECT_TRUE(t.ok());
  return *t;
}

// An axis-aligned rectangle at x = const facing the origin, y in [y0, y1], z in [z0, z1].
void AddWall(TriangleMesh* m, float x, float y0, float y1, float z0, float z1, SurfaceClass c) {
  m->AddTriangle({x, y0, z0}, {x, y1, z0}, {x, y1, z1}, c, 0.5f);
  m->AddTriangle({x, y0, z0}, {x, y1, z1}, {x, y0, z1}, c, 0.5f);
}

Hdl64Lidar::Options Clean() {
  Hdl64Lidar::Options o;
  o.range_noise_sigma_m = 0.0;
  o.dropout_base = 0.0;
  o.dropout_far = 0.0;
  return o;
}

double Std(const std::vector<double>& v) {
  double s = 0, s2 = 0;
  for (double x : v) {
    s += x;
    s2 += x * x;
  }
  const double m = s / v.size();
  return std::sqrt(std::max(0.0, s2 / v.size() - m * m));
}

// ---- per-laser intrinsic calibration residuals ------------------------------------------------

TEST(LaserIntrinsicsTest, FixedForASeedWithTheStatedSpread) {
  Hdl64Lidar::Options o;
  EXPECT_EQ(Hdl64Lidar(o).LaserErrors(3)[10].range_offset_m, 0.0);  // off by default
  o.num_beams = 256;  // more lasers for a tighter estimate of the spread
  o.EnableLaserIntrinsicErrors();
  ASSERT_TRUE(o.Validate().ok());
  const Hdl64Lidar lidar(o);
  const auto a = lidar.LaserErrors(3), b = lidar.LaserErrors(3), c = lidar.LaserErrors(4);
  ASSERT_EQ(a.size(), 256u);
  std::vector<double> el, az, off, sc;
  int same_as_other_seed = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].elevation_deg, b[i].elevation_deg);
    EXPECT_EQ(a[i].range_offset_m, b[i].range_offset_m);
    same_as_other_seed += a[i].range_offset_m == c[i].range_offset_m ? 1 : 0;
    el.push_back(a[i].elevation_deg);
    az.push_back(a[i].azimuth_deg);
    off.push_back(a[i].range_offset_m);
    sc.push_back(a[i].range_scale);
  }
  EXPECT_EQ(same_as_other_seed, 0);
  EXPECT_NEAR(Std(el), 0.03, 0.006);
  EXPECT_NEAR(Std(az), 0.03, 0.006);
  EXPECT_NEAR(Std(off), 0.02, 0.004);
  EXPECT_NEAR(Std(sc), 1e-3, 2e-4);
}

TEST(LaserIntrinsicsTest, TheDrivesResidualsAreInScenarioJson) {
  const testing::ScopedTempDir dir("sim_laser_errors");
  DriveSimulator::Options o;
  o.scenario = "demo";
  o.duration_s = 0.2;
  o.write_scene_cloud = false;
  o.lidar.EnableLaserIntrinsicErrors();
  auto sim = DriveSimulator::Create(o);
  ASSERT_TRUE(sim.ok()) << sim.status().ToString();
  auto summary = sim->Run(dir.path);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  std::ifstream f(summary->drive_dir / "ground_truth" / "scenario.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  const auto& e = j.at("lidar").at("laser_errors");
  ASSERT_EQ(e.size(), 64u);
  // The table the scans were simulated with, and its range offsets have the stated spread.
  const auto used = Hdl64Lidar(o.lidar).LaserErrors(MixSeed(o.seed, 50));
  double sum2 = 0.0;
  for (size_t b = 0; b < e.size(); ++b) {
    ASSERT_EQ(e[b].size(), 4u);
    EXPECT_EQ(e[b][0].get<double>(), used[b].elevation_deg);
    EXPECT_EQ(e[b][2].get<double>(), used[b].range_offset_m);
    sum2 += e[b][2].get<double>() * e[b][2].get<double>();
  }
  EXPECT_NEAR(std::sqrt(sum2 / 64.0), 0.02, 0.008);
  // Without the model there is no table.
  o.lidar = Hdl64Lidar::Options();
  const testing::ScopedTempDir dir2("sim_laser_errors_off");
  auto off = DriveSimulator::Create(o);
  ASSERT_TRUE(off.ok());
  auto s2 = off->Run(dir2.path);
  ASSERT_TRUE(s2.ok());
  std::ifstream f2(s2->drive_dir / "ground_truth" / "scenario.json");
  EXPECT_FALSE(nlohmann::json::parse(f2).at("lidar").contains("laser_errors"));
}

TEST(LaserIntrinsicsTest, EachLaserMeasuresWithItsOwnResiduals) {
  // A wall at x = 20 and a ground plane at z = -1.73; no noise, no dropouts.
  TriangleMesh m;
  m.AddTriangle({20, -500, -100}, {20, 500, -100}, {20, 0, 500}, SurfaceClass::kBuilding, 0.5f);
  m.AddTriangle({-500, -500, -1.73f}, {500, -500, -1.73f}, {0, 500, -1.73f}, SurfaceClass::kRoad,
                0.2f);
  auto world = CityWorld::FromMesh(std::move(m));
  ASSERT_TRUE(world.ok());
  const ReferenceTrajectory traj = StaticTrajectory();
  Hdl64Lidar::Options o = Clean();
  o.EnableLaserIntrinsicErrors();
  const Hdl64Lidar lidar(o);
  const uint64_t seed = 17;
  const auto err = lidar.LaserErrors(seed);
  const auto out = lidar.Simulate(*world, traj, Eigen::Isometry3d::Identity(), 0.5, 0, seed, 2);
  const double deg = M_PI / 180.0;
  std::map<int, std::vector<double>> wall_residual, ground_residual;
  for (size_t i = 0; i < out.scan.cloud.size(); ++i) {
    const int b = out.beams[i];
    const Eigen::Vector3d p = out.scan.cloud.points()[i].cast<double>();
    const double r = p.norm();
    const double el = lidar.elevations_deg()[b] * deg, el_true = el + err[b].elevation_deg * deg;
    if (out.surfaces[i] == SurfaceClass::kBuilding) {
      // The true ray (azimuth written + azimuth residual) meets x = 20 at r_true.
      const double az_true = std::atan2(p.y(), p.x()) + err[b].azimuth_deg * deg;
      const double r_true = 20.0 / (std::cos(el_true) * std::cos(az_true));
      wall_residual[b].push_back(r - ((1.0 + err[b].range_scale) * r_true + err[b].range_offset_m));
    } else {
      const double r_true = -1.73 / std::sin(el_true);
      const double r_read = (1.0 + err[b].range_scale) * r_true + err[b].range_offset_m;
      ground_residual[b].push_back(p.z() - r_read * std::sin(el));  // written at nominal elevation
    }
  }
  int checked = 0;
  for (const auto& [b, v] : wall_residual) {
    if (v.size() < 20) continue;
    for (double x : v) EXPECT_NEAR(x, 0.0, 2e-3) << "beam " << b;
    ++checked;
  }
  for (const auto& [b, v] : ground_residual) {
    for (double x : v) EXPECT_NEAR(x, 0.0, 2e-3) << "beam " << b;
  }
  EXPECT_GT(checked, 10);
  // And the residuals matter: ground heights spread by centimetres between the lasers.
  std::vector<double> mean_z;
  for (size_t i = 0; i < out.scan.cloud.size(); ++i) {
    if (out.surfaces[i] != SurfaceClass::kRoad) continue;
    const Eigen::Vector3f p = out.scan.cloud.points()[i];
    if (p.head<2>().norm() < 15.0) mean_z.push_back(p.z());
  }
  EXPECT_GT(Std(mean_z), 0.005);
}

// ---- beam divergence and mixed pixels ---------------------------------------------------------

// A foreground wall at x = 10 ending at y = 0.01 (its edge seen at azimuth 1 mrad, between the
// firings at +-1.5 mrad; the other end too far to return) before a background wall at x = 10 + gap.
// A static sensor: every ring meets the vertical edge at the same azimuths.
struct EdgeScan {
  int returns = 0, in_between = 0, in_between_off_edge = 0, out_of_bounds = 0;
};
EdgeScan ScanEdge(float gap, double divergence_rad) {
  TriangleMesh m;
  AddWall(&m, 10.f, -500.f, 0.01f, -30.f, 30.f, SurfaceClass::kBuilding);
  AddWall(&m, 10.f + gap, -100.f, 100.f, -60.f, 60.f, SurfaceClass::kBuilding);
  auto world = CityWorld::FromMesh(std::move(m));
  EXPECT_TRUE(world.ok());
  Hdl64Lidar::Options o = Clean();
  o.beam_divergence_rad = divergence_rad;
  const auto out = Hdl64Lidar(o).Simulate(*world, StaticTrajectory(), Eigen::Isometry3d::Identity(),
                                          0.5, 0, 1, 2);
  EdgeScan s;
  for (const auto& p : out.scan.cloud.points()) {
    // Within 0.5 rad of the edge (at grazing incidence far out, a footprint straddles a steep
    // range gradient, and its energy-weighted range is biased low: real, but not this test).
    if (p.x() <= 0.f || std::abs(std::atan2(p.y(), p.x())) > 0.5) continue;
    ++s.returns;
    if (p.x() < 10.f - 2e-3f || p.x() > 10.f + gap + 2e-3f) ++s.out_of_bounds;
    if (p.x() > 10.05f && p.x() < 10.f + gap - 0.05f) {
      ++s.in_between;
      // Within a firing step and the footprint of the edge direction (azimuth 0).
      if (std::abs(std::atan2(p.y(), p.x())) > 3.1e-3 + divergence_rad) ++s.in_between_off_edge;
    }
  }
  return s;
}

TEST(BeamDivergenceTest, MixedPixelsOnlyAtADepthEdgeAndOnlyWhenOn) {
  const EdgeScan off = ScanEdge(3.f, 0.0);
  EXPECT_GT(off.returns, 15000);
  EXPECT_EQ(off.in_between, 0);
  EXPECT_EQ(off.out_of_bounds, 0);
  const EdgeScan on = ScanEdge(3.f, 2e-3);
  // The background firing next to the edge (+1.5 mrad) has a footprint sub-ray at +0.83 mrad on
  // the foreground: one mixed pixel per ring.
  EXPECT_GE(on.in_between, 50);
  EXPECT_LE(on.in_between, 64);
  EXPECT_EQ(on.in_between_off_edge, 0);
  EXPECT_EQ(on.out_of_bounds, 0);
}

TEST(BeamDivergenceTest, FarApartEchoesAreNotBlended) {
  // 10 m behind the edge: beyond mixed_pixel_max_separation_m (5 m), the strongest echo wins.
  const EdgeScan on = ScanEdge(10.f, 2e-3);
  EXPECT_EQ(on.in_between, 0);
  EXPECT_EQ(on.out_of_bounds, 0);
}

// ---- volumetric vegetation -----------------------------------------------------------------

TEST(VolumetricVegetationTest, ReturnsSpreadThroughTheVolumeWithBeerLambertDepths) {
  // A 4 m deep box of foliage (x 8..12, mean free path 2 m) before a wall at x = 30.
  TriangleMesh m;
  m.AddBox({10, 0, 0}, Eigen::Matrix3f::Identity(), {2, 3, 3}, SurfaceClass::kFoliage, 0.3f);
  m.MarkVolume(0, 2.0f);
  AddWall(&m, 30.f, -50.f, 50.f, -50.f, 50.f, SurfaceClass::kBuilding);
  m.mean_free_path_m.resize(m.triangles.size(), 0.f);
  auto world = CityWorld::FromMesh(std::move(m));
  ASSERT_TRUE(world.ok());
  const int n = 20000;
  std::vector<Eigen::Vector3f> o(n, Eigen::Vector3f::Zero()), d(n);
  std::vector<uint64_t> keys(n);
  std::mt19937 gen(5);
  std::uniform_real_distribution<float> u(-0.1f, 0.1f);
  for (int i = 0; i < n; ++i) {
    d[i] = Eigen::Vector3f(1.f, u(gen), u(gen)).normalized();
    keys[i] = 1000 + i;
  }
  std::vector<RayHit> hits(n);
  world->IntersectScattering(o.data(), d.data(), keys.data(), n, 1.f, 100.f, hits.data());
  int wall = 0, inside = 0, deep = 0;
  double depth_sum = 0.0;
  for (int i = 0; i < n; ++i) {
    ASSERT_GT(hits[i].range_m, 0.f);
    const double x = hits[i].range_m * d[i].x();
    if (hits[i].surface == SurfaceClass::kBuilding) {
      EXPECT_NEAR(x, 30.0, 1e-3);
      ++wall;
      continue;
    }
    ASSERT_TRUE(hits[i].volume_return);
    ASSERT_GE(x, 8.0 - 1e-3);
    ASSERT_LE(x, 12.0 + 1e-3);
    ++inside;
    depth_sum += x - 8.0;
    deep += x > 9.0 ? 1 : 0;
  }
  // Transmission exp(-4 / 2) through the whole box; a truncated exponential inside.
  const double pass = std::exp(-2.0);
  EXPECT_NEAR(static_cast<double>(wall) / n, pass, 0.015);
  const double mean_trunc = 2.0 - 4.0 * pass / (1.0 - pass);
  EXPECT_NEAR(depth_sum / inside, mean_trunc, 0.05);
  EXPECT_NEAR(static_cast<double>(deep) / inside, (std::exp(-0.5) - pass) / (1.0 - pass), 0.02);
  // Plain Intersect sees only the hull.
  std::vector<RayHit> plain(n);
  world->Intersect(o.data(), d.data(), n, 1.f, 100.f, plain.data());
  for (int i = 0; i < 100; ++i) {
    EXPECT_NEAR(plain[i].range_m * d[i].x(), 8.0, 1e-3);
    EXPECT_TRUE(plain[i].entering);
    EXPECT_GT(plain[i].mean_free_path_m, 0.f);
  }
}

TEST(VolumetricVegetationTest, CityCrownsBecomeVolumesAndTheRestStaysTheSame) {
  DriveSimulator::Options o;
  o.scenario = "demo";
  o.duration_s = 10.0;
  auto plain = DriveSimulator::Create(o);
  ASSERT_TRUE(plain.ok()) << plain.status().ToString();
  o.world.volumetric_vegetation = true;
  auto veg = DriveSimulator::Create(o);
  ASSERT_TRUE(veg.ok()) << veg.status().ToString();
  const auto& a = plain->world().stats();
  const auto& b = veg->world().stats();
  EXPECT_EQ(a.num_buildings, b.num_buildings);
  EXPECT_EQ(a.num_cars, b.num_cars);
  EXPECT_EQ(a.num_poles, b.num_poles);
  EXPECT_EQ(a.num_trees, b.num_trees);
  EXPECT_GT(b.num_trees, 0);
  EXPECT_EQ(a.num_hedges, 0);
  EXPECT_TRUE(plain->world().mesh().mean_free_path_m.empty());
  const auto& mfp = veg->world().mesh().mean_free_path_m;
  ASSERT_EQ(mfp.size(), veg->world().mesh().triangles.size());
  EXPECT_GT(std::count_if(mfp.begin(), mfp.end(), [](float x) { return x > 0.f; }),
            100 * b.num_trees);
}

// ---- ground roughness --------------------------------------------------------------------------

TEST(GroundRoughnessTest, TextureHasTheStatedRmsPerClass) {
  TriangleMesh m;
  m.AddTriangle({-500, -500, 0}, {500, -500, 0}, {0, 500, 0}, SurfaceClass::kRoad, 0.2f);
  CityWorld::Options o;
  o.EnableGroundRoughness();
  auto world = CityWorld::FromMesh(m, o);
  ASSERT_TRUE(world.ok());
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> u(-200.0, 200.0);
  for (auto [cls, rms] : {std::pair<SurfaceClass, double>{SurfaceClass::kRoad, 0.005},
                          {SurfaceClass::kSidewalk, 0.008},
                          {SurfaceClass::kTerrain, 0.03}}) {
    std::vector<double> h;
    for (int i = 0; i < 40000; ++i) h.push_back(world->RoughnessHeight(u(gen), u(gen), cls));
    double s2 = 0, s = 0;
    for (double x : h) {
      s += x;
      s2 += x * x;
    }
    EXPECT_NEAR(std::sqrt(s2 / h.size()), rms, 0.06 * rms) << SurfaceClassName(cls);
    EXPECT_NEAR(s / h.size(), 0.0, 0.05 * rms);
  }
  EXPECT_EQ(world->RoughnessHeight(1.0, 2.0, SurfaceClass::kBuilding), 0.0);
  // Fixed in the world: the same height at the same place; another seed, another texture.
  EXPECT_EQ(world->RoughnessHeight(1.3, 2.7, SurfaceClass::kRoad),
            world->RoughnessHeight(1.3, 2.7, SurfaceClass::kRoad));
  o.seed = 2;
  auto other = CityWorld::FromMesh(m, o);
  ASSERT_TRUE(other.ok());
  EXPECT_NE(world->RoughnessHeight(1.3, 2.7, SurfaceClass::kRoad),
            other->RoughnessHeight(1.3, 2.7, SurfaceClass::kRoad));
}

TEST(GroundRoughnessTest, ScansSeeTheRoughSurface) {
  TriangleMesh m;
  m.AddTriangle({-500, -500, -1.73f}, {500, -500, -1.73f}, {0, 500, -1.73f}, SurfaceClass::kRoad,
                0.2f);
  CityWorld::Options wo;
  wo.road_roughness_rms_m = 0.01;
  auto world = CityWorld::FromMesh(m, wo);
  ASSERT_TRUE(world.ok());
  const auto out = Hdl64Lidar(Clean()).Simulate(*world, StaticTrajectory(),
                                                Eigen::Isometry3d::Identity(), 0.5, 0, 1, 2);
  std::vector<double> dz, miss;
  for (const auto& p : out.scan.cloud.points()) {
    if (p.head<2>().norm() > 8.f) continue;
    dz.push_back(p.z() + 1.73);
    miss.push_back(
        std::abs(p.z() - (-1.73 + world->RoughnessHeight(p.x(), p.y(), SurfaceClass::kRoad))));
  }
  ASSERT_GT(dz.size(), 10000u);
  EXPECT_NEAR(Std(dz), 0.01, 0.002);
  std::nth_element(miss.begin(), miss.begin() + miss.size() / 2, miss.end());
  EXPECT_LT(miss[miss.size() / 2], 1e-3);  // the points lie on the textured surface
}

TEST(RealismOptionsTest, AllModelsOnIndependentOfThreadsAndDifferentFromOff) {
  DriveSimulator::Options o;
  o.scenario = "demo";
  o.duration_s = 10.0;
  o.world.volumetric_vegetation = true;
  o.world.EnableGroundRoughness();
  auto sim = DriveSimulator::Create(o);
  ASSERT_TRUE(sim.ok()) << sim.status().ToString();
  Hdl64Lidar::Options lo;
  lo.EnableLaserIntrinsicErrors();
  lo.beam_divergence_rad = 2e-3;
  const Hdl64Lidar lidar(lo);
  const Eigen::Isometry3d T_body_lidar = KittiTLidarBody().inverse();
  const double t = sim->first_scan_s() + 3.0;
  const auto a = lidar.Simulate(sim->world(), sim->trajectory(), T_body_lidar, t, 30, 9, 1);
  const auto b = lidar.Simulate(sim->world(), sim->trajectory(), T_body_lidar, t, 30, 9, 3);
  ASSERT_EQ(a.scan.cloud.size(), b.scan.cloud.size());
  ASSERT_GT(a.scan.cloud.size(), 50000u);
  for (size_t i = 0; i < a.scan.cloud.size(); ++i) {
    ASSERT_EQ(a.scan.cloud.points()[i], b.scan.cloud.points()[i]) << i;
    ASSERT_EQ(a.scan.cloud.intensities()[i], b.scan.cloud.intensities()[i]) << i;
  }
  // The models change the scan: foliage returns inside crowns, other ranges.
  const auto off =
      Hdl64Lidar().Simulate(sim->world(), sim->trajectory(), T_body_lidar, t, 30, 9, 2);
  size_t same = 0;
  for (size_t i = 0; i < std::min(off.scan.cloud.size(), a.scan.cloud.size()); ++i)
    same += off.scan.cloud.points()[i] == a.scan.cloud.points()[i] ? 1 : 0;
  EXPECT_LT(same, a.scan.cloud.size() / 10);
}

TEST(RealismOptionsTest, ValidateNamesTheField) {
  Hdl64Lidar::Options l;
  l.beam_divergence_rad = -1.0;
  EXPECT_NE(l.Validate().message().find("beam_divergence_rad"), std::string::npos);
  l = Hdl64Lidar::Options();
  l.laser_range_offset_sigma_m = 1.0;
  EXPECT_NE(l.Validate().message().find("laser_range_offset_sigma_m"), std::string::npos);
  CityWorld::Options w;
  w.terrain_roughness_rms_m = -0.1;
  EXPECT_NE(w.Validate().message().find("terrain_roughness_rms_m"), std::string::npos);
  w = CityWorld::Options();
  w.foliage_mean_free_path_m = 0.0;
  EXPECT_NE(w.Validate().message().find("foliage_mean_free_path_m"), std::string::npos);
}

}  // namespace
}  // namespace slam_mms::sim
