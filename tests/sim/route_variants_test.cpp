// Route variants of the scripted scenarios: several drives through overlapping streets of one city
// (one world for every variant of a seed, one world frame, their own times and sensor noise).
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "slam_mms/io/kitti_timestamp.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms/sim/city_world.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms/sim/reference_trajectory.hpp"
#include "testing/test_data.hpp"

namespace slam_mms::sim {
namespace {

// Distance from q to the polyline of the samples' ground track [m] (brute force).
double DistanceToRoute(const Eigen::Vector2d& q, const std::vector<PoseSample>& route) {
  double best = 1e30;
  for (size_t i = 0; i + 1 < route.size(); ++i) {
    const Eigen::Vector2d a = route[i].p_world.head<2>();
    const Eigen::Vector2d d = route[i + 1].p_world.head<2>() - a;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((q - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (q - a - t * d).norm());
  }
  return best;
}

// Length of `route` within `max_distance_m` of `other` (or, with `invert`, farther than it from
// every route of `others`) [m].
double LengthNear(const std::vector<PoseSample>& route,
                  const std::vector<const std::vector<PoseSample>*>& others, double max_distance_m,
                  bool invert) {
  double length = 0.0;
  for (size_t i = 1; i < route.size(); ++i) {
    const Eigen::Vector2d q = route[i].p_world.head<2>();
    bool near_any = false;
    for (const auto* o : others) near_any = near_any || DistanceToRoute(q, *o) < max_distance_m;
    if (near_any != invert) length += (route[i].p_world - route[i - 1].p_world).head<2>().norm();
  }
  return length;
}

double RouteLength(const std::vector<PoseSample>& route) {
  double length = 0.0;
  for (size_t i = 1; i < route.size(); ++i)
    length += (route[i].p_world - route[i - 1].p_world).head<2>().norm();
  return length;
}

// FNV-1a over the mesh's vertices, triangles, classes and albedos.
uint64_t MeshHash(const TriangleMesh& m) {
  uint64_t h = 1469598103934665603ull;
  auto add = [&h](const void* p, size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) {
      h ^= b[i];
      h *= 1099511628211ull;
    }
  };
  for (const auto& v : m.vertices) add(v.data(), sizeof(float) * 3);
  for (const auto& t : m.triangles) add(t.data(), sizeof(int) * 3);
  for (const auto c : m.classes) add(&c, sizeof(c));
  for (const auto a : m.albedo) add(&a, sizeof(a));
  return h;
}

DriveSimulator::Options Variant(const std::string& scenario, int k) {
  DriveSimulator::Options o;
  o.scenario = scenario;
  o.seed = 7;
  o.route_variant = k;
  o.lead_in_s = 4.0;
  o.duration_s = 0.3;
  return o;
}

TEST(RouteVariantsTest, VariantZeroIsTheScenarioRoute) {
  for (const std::string scenario : {"demo", "default"}) {
    ASSERT_EQ(NumRouteVariants(scenario), 3);
    auto v0 = RouteVariantSamples(scenario, 0);
    ASSERT_TRUE(v0.ok()) << v0.status().ToString();
    const auto route = scenario == "demo" ? DemoUrbanRouteSamples() : DefaultUrbanRouteSamples();
    ASSERT_EQ(v0->size(), route.size());
    for (size_t i = 0; i < route.size(); ++i) {
      ASSERT_EQ(route[i].t_s, (*v0)[i].t_s);
      ASSERT_EQ(route[i].p_world, (*v0)[i].p_world);
      ASSERT_EQ(route[i].rpy_rad, (*v0)[i].rpy_rad);
    }
  }
  EXPECT_EQ(NumRouteVariants("long"), 0);
}

TEST(RouteVariantsTest, EveryPairSharesStreetsAndEachHasItsOwn) {
  for (const std::string scenario : {"demo", "default"}) {
    std::vector<std::vector<PoseSample>> routes;
    for (int k = 0; k < NumRouteVariants(scenario); ++k) {
      auto r = RouteVariantSamples(scenario, k);
      ASSERT_TRUE(r.ok()) << r.status().ToString();
      routes.push_back(*r);
    }
    const bool demo = scenario == "demo";
    for (size_t k = 0; k < routes.size(); ++k) {
      SCOPED_TRACE(scenario + " variant " + std::to_string(k));
      // Durations and lengths: demo about a minute, default about three.
      EXPECT_GT(routes[k].back().t_s, demo ? 55.0 : 170.0);
      EXPECT_LT(routes[k].back().t_s, demo ? 85.0 : 220.0);
      EXPECT_GT(RouteLength(routes[k]), demo ? 350.0 : 1200.0);
      // All variants start in the one city frame, not re-zeroed (variant 0 at the origin).
      if (k > 0) {
        EXPECT_GT(routes[k].front().p_world.head<2>().norm(), 50.0);
      }
      std::vector<const std::vector<PoseSample>*> others;
      for (size_t j = 0; j < routes.size(); ++j) {
        if (j == k) continue;
        others.push_back(&routes[j]);
        // Streets driven by both (in either direction): within 3 m of the other's path.
        EXPECT_GT(LengthNear(routes[k], {&routes[j]}, 3.0, false), demo ? 100.0 : 200.0)
            << "shared with variant " << j;
      }
      // A street of its own: more than 10 m from every other variant's path.
      EXPECT_GT(LengthNear(routes[k], others, 10.0, true), demo ? 60.0 : 100.0);
    }
  }
}

TEST(RouteVariantsTest, InvalidVariantIsRejectedNamingRouteVariant) {
  for (const int k : {3, -2, 100}) {
    const Status s = Variant("demo", k).Validate();
    EXPECT_FALSE(s.ok()) << k;
    EXPECT_NE(s.message().find("route_variant"), std::string::npos) << s.ToString();
  }
  DriveSimulator::Options long_drive = Variant("long", 0);
  long_drive.duration_s = 10.0;
  const Status s = long_drive.Validate();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("route_variant"), std::string::npos) << s.ToString();
  auto samples = RouteVariantSamples("default", 3);
  ASSERT_FALSE(samples.ok());
  EXPECT_NE(samples.status().message().find("route_variant"), std::string::npos);
  EXPECT_FALSE(DriveSimulator::Create(Variant("demo", 3)).ok());
  EXPECT_TRUE(Variant("demo", -1).Validate().ok());  // no variants: as before
  EXPECT_TRUE(Variant("default", 2).Validate().ok());
}

TEST(RouteVariantsTest, EveryVariantDrivesThroughTheSameWorld) {
  std::vector<DriveSimulator> sims;
  for (int k = 0; k < 3; ++k) {
    auto sim = DriveSimulator::Create(Variant("demo", k));
    ASSERT_TRUE(sim.ok()) << sim.status().ToString();
    sims.push_back(std::move(*sim));
  }
  const TriangleMesh& mesh0 = sims[0].world().mesh();
  for (int k = 1; k < 3; ++k) {
    EXPECT_EQ(sims[k].world().mesh().triangles.size(), mesh0.triangles.size());
    EXPECT_EQ(MeshHash(sims[k].world().mesh()), MeshHash(mesh0)) << "variant " << k;
  }
  // The world has every variant's streets: straight down from above the body at every second of
  // each variant's drive, variant 0's world has road (or a lane marking) 0.93 m below the body.
  const CityWorld& world = sims[0].world();
  for (int k = 0; k < 3; ++k) {
    const ReferenceTrajectory& traj = sims[k].trajectory();
    int checked = 0;
    for (double t = traj.start_s(); t <= traj.end_s(); t += 1.0, ++checked) {
      const Eigen::Vector3f p = traj.Pose(t).translation().cast<float>();
      const Eigen::Vector3f o = p + Eigen::Vector3f(0.f, 0.f, 1.0f);
      const Eigen::Vector3f down(0.f, 0.f, -1.f);
      RayHit hit;
      world.Intersect(&o, &down, 1, 0.0f, 10.0f, &hit);
      ASSERT_GT(hit.range_m, 0.0f) << "variant " << k << " t " << t;
      EXPECT_NEAR(hit.range_m, 1.93f, 0.15f) << "variant " << k << " t " << t;
      EXPECT_TRUE(hit.surface == SurfaceClass::kRoad || hit.surface == SurfaceClass::kMarking)
          << "variant " << k << " t " << t << ": " << SurfaceClassName(hit.surface);
    }
    EXPECT_GT(checked, 60);
  }
  // Without a variant, the world follows the simulated span of the route alone (as before).
  DriveSimulator::Options alone = Variant("demo", -1);
  auto single = DriveSimulator::Create(alone);
  ASSERT_TRUE(single.ok());
  EXPECT_LT(single->world().mesh().triangles.size(), mesh0.triangles.size());
}

TEST(RouteVariantsTest, OneWorldFrameOwnTimesAndNoise) {
  auto alone = DriveSimulator::Create(Variant("demo", -1));
  auto v0 = DriveSimulator::Create(Variant("demo", 0));
  auto v1 = DriveSimulator::Create(Variant("demo", 1));
  ASSERT_TRUE(alone.ok() && v0.ok() && v1.ok());
  // Variant 0 is the route without variants: the same ground truth, stamps and noise.
  const ReferenceTrajectory& t_alone = alone->trajectory();
  const ReferenceTrajectory& t0 = v0->trajectory();
  EXPECT_EQ(t0.epoch().nanoseconds(), t_alone.epoch().nanoseconds());
  for (double t = t0.start_s(); t <= t0.end_s(); t += 5.0) {
    EXPECT_LT((t0.Pose(t).matrix() - t_alone.Pose(t).matrix()).norm(), 1e-12) << t;
  }
  EXPECT_EQ(v0->sensor_seed(), alone->sensor_seed());
  EXPECT_EQ(v0->options().drive_id, 1);
  // Variant 1: one hour later, its own noise, drive 2, and its route where it lies in the city.
  EXPECT_NEAR(v1->trajectory().epoch().SecondsSince(t0.epoch()), 3600.0, 1e-9);
  EXPECT_NE(v1->sensor_seed(), v0->sensor_seed());
  EXPECT_EQ(v1->options().drive_id, 2);
  const auto route1 = RouteVariantSamples("demo", 1);
  ASSERT_TRUE(route1.ok());
  const Eigen::Vector3d start1 = v1->trajectory().Pose(v1->trajectory().start_s()).translation();
  EXPECT_LT((start1 - route1->front().p_world).norm(), 0.1);
  DriveSimulator::Options named = Variant("demo", 2);
  named.drive_id = 17;
  auto v2 = DriveSimulator::Create(named);
  ASSERT_TRUE(v2.ok());
  EXPECT_EQ(v2->options().drive_id, 17);  // an explicit drive id wins
}

TEST(RouteVariantsTest, WrittenDriveRecordsTheVariantInTheCommonFrame) {
  const testing::ScopedTempDir dir("sim_route_variant");
  auto sim = DriveSimulator::Create(Variant("demo", 2));
  ASSERT_TRUE(sim.ok()) << sim.status().ToString();
  auto summary = sim->Run(dir.path);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->drive_name, "2026_01_15_drive_0003_sync");
  std::ifstream f(summary->drive_dir / "ground_truth" / "scenario.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j.at("route_variant").get<int>(), 2);
  EXPECT_EQ(j.at("num_route_variants").get<int>(), 3);
  EXPECT_EQ(j.at("sensor_seed").get<uint64_t>(), sim->sensor_seed());
  EXPECT_DOUBLE_EQ(j.at("origin_wgs84").at("latitude_deg").get<double>(),
                   DriveSimulator::Options().origin_latitude_deg);
  // The ground truth is in the world frame, where variant 2's route starts (not re-zeroed).
  auto gt = ReadTrajectoryTum(summary->drive_dir / "ground_truth" / "poses_100hz.tum");
  ASSERT_TRUE(gt.ok()) << gt.status().ToString();
  ASSERT_GT(gt->size(), 10u);
  const auto route2 = RouteVariantSamples("demo", 2);
  ASSERT_TRUE(route2.ok());
  EXPECT_LT((gt->poses().front().T_world_body.translation() - route2->front().p_world).norm(), 0.1);
  // Stamps: from two hours after the scenario's start time (variant 0's).
  auto start = ParseKittiTimestamp(DriveSimulator::Options().start_time);
  ASSERT_TRUE(start.ok());
  EXPECT_NEAR(gt->poses().front().stamp.SecondsSince(*start), 7200.0, 0.02);
}

}  // namespace
}  // namespace slam_mms::sim
