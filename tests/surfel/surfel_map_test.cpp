#include "slam_mms/surfel/surfel_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <utility>

#include "slam_mms/surfel/range_projection.hpp"
#include "surfel/synthetic_surfels.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

// A scene of planes n . x = offset (world frame) plus an optional box (a dynamic object).
struct Plane {
  Eigen::Vector3d n;
  double offset;
};
struct Scene {
  std::vector<Plane> planes = {
      {{0, 0, 1}, -1.73}, {{0, 1, 0}, 6.0}, {{0, -1, 0}, 6.0}, {{1, 0, 0}, 40.0}};
  bool with_box = false;
  Eigen::Vector3d box_min{12.0, -1.0, -1.73}, box_max{14.0, 1.0, 0.5};
};

double RayCast(const Scene& scene, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double best = std::numeric_limits<double>::infinity();
  for (const Plane& p : scene.planes) {
    const double den = p.n.dot(d);
    if (std::abs(den) < 1e-9) continue;
    const double t = (p.offset - p.n.dot(o)) / den;
    if (t > 0 && t < best) best = t;
  }
  if (scene.with_box) {
    double t0 = 0, t1 = best;
    for (int a = 0; a < 3; ++a) {
      const double inv = 1.0 / d[a];
      double ta = (scene.box_min[a] - o[a]) * inv, tb = (scene.box_max[a] - o[a]) * inv;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (t0 <= t1 && t0 > 0) best = t0;
  }
  return best;
}

PointCloud SimulateScan(const Scene& scene, const RangeProjection& proj,
                        const Eigen::Isometry3d& T_world_sensor, double noise_m,
                        std::mt19937* rng) {
  std::uniform_real_distribution<float> jitter(0.05f, 0.95f);
  std::normal_distribution<double> noise(0.0, noise_m);
  PointCloud cloud;
  for (int r = 0; r < proj.rows(); ++r) {
    for (int c = 0; c < proj.cols(); ++c) {
      const Eigen::Vector3d d_s =
          proj.Unproject(c + jitter(*rng), r + jitter(*rng), 1.0f).cast<double>().normalized();
      const Eigen::Vector3d d_w = T_world_sensor.linear() * d_s;
      const double t = RayCast(scene, T_world_sensor.translation(), d_w);
      if (!(t < 80.0)) continue;
      cloud.Add(((t + noise(*rng)) * d_s).cast<float>());
    }
  }
  return cloud;
}

Eigen::Isometry3d PoseAt(double x) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, 0.3, 0.0);
  T.linear() = Eigen::AngleAxisd(0.02 * x, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

double DistanceToScene(const Scene& scene, const Eigen::Vector3f& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Plane& pl : scene.planes) {
    best = std::min(best, std::abs(pl.n.dot(p.cast<double>()) - pl.offset));
  }
  return best;
}

TEST(SurfelMapTest, PlaneSceneConvergesAndGainsConfidence) {
  const Scene scene;
  SurfelMap map;
  const RangeProjection& proj = map.renderer().projection();
  std::mt19937 rng(3);
  VertexNormalMap scan;
  std::vector<SurfelIntegrationStats> stats;
  for (int f = 0; f < 10; ++f) {
    const Eigen::Isometry3d T = PoseAt(0.4 * f);
    const PointCloud cloud = SimulateScan(scene, proj, T, 0.02, &rng);
    proj.ComputeVertexNormalMap(cloud, &scan);
    auto s = map.Integrate(scan, T, Timestamp::FromNanoseconds(1000000000LL * (f + 1)));
    ASSERT_TRUE(s.ok()) << s.status().ToString();
    stats.push_back(*s);
  }
  // First scan creates roughly one surfel per pixel with a normal; later scans mostly re-observe.
  EXPECT_GT(stats[0].num_created, 100000);
  for (int f = 1; f < 10; ++f) {
    EXPECT_GT(stats[f].num_explained, scan.CountNormals() * 7 / 10) << "frame " << f;
    EXPECT_GT(stats[f].num_confirmed, stats[0].num_created / 3) << "frame " << f;
    EXPECT_LT(stats[f].num_created, stats[0].num_created / 3) << "frame " << f;
  }
  EXPECT_EQ(map.frame_count(), 10);
  // Confirmed surfels converge onto the planes: closer than the single-measurement noise and than
  // the surfels made from one measurement; confidence grew with the number of confirmations.
  double sum_updated = 0, sum_new = 0, conf_updated = 0;
  int n_updated = 0, n_new = 0;
  for (uint32_t id = 0; id < map.surfels().size(); ++id) {
    if (!map.IsAlive(id)) continue;
    const Surfel& s = map.surfels()[id];
    const double dist = DistanceToScene(scene, s.position);
    EXPECT_NEAR(s.normal.norm(), 1.0f, 1e-4f);
    EXPECT_GE(s.radius, 0.05f);
    EXPECT_LE(s.radius, 1.0f);
    if (s.num_updates >= 5) {
      sum_updated += dist;
      conf_updated += s.confidence;
      ++n_updated;
    } else if (s.num_updates == 0) {
      sum_new += dist;
      ++n_new;
    }
  }
  ASSERT_GT(n_updated, 20000);
  ASSERT_GT(n_new, 1000);
  const double mean_updated = sum_updated / n_updated;
  const double mean_new = sum_new / n_new;
  EXPECT_LT(mean_updated, 0.012);  // single measurements: E|N(0, 2 cm)| = 1.6 cm along the ray
  EXPECT_LT(mean_updated, 0.75 * mean_new);
  EXPECT_GT(conf_updated / n_updated, 1.0);  // >= 5 confirmations of up to +0.405 each
}

// With integrate_current_submap_only, a scan of an already mapped place is not fused into the
// older submap's surfels: the new submap gets its own surfels and the old ones are untouched.
TEST(SurfelMapTest, IntegrateCurrentSubmapOnlyLeavesOtherSubmapsAlone) {
  const Scene scene;
  for (const bool only_current : {false, true}) {
    SurfelMapOptions options;
    options.integrate_current_submap_only = only_current;
    auto created = SurfelMap::Create(options);
    ASSERT_TRUE(created.ok());
    SurfelMap map = std::move(created).value();
    const RangeProjection& proj = map.renderer().projection();
    std::mt19937 rng(5);
    VertexNormalMap scan;
    const Eigen::Isometry3d T = PoseAt(0.0);
    proj.ComputeVertexNormalMap(SimulateScan(scene, proj, T, 0.02, &rng), &scan);
    ASSERT_TRUE(map.Integrate(scan, T, Timestamp::FromNanoseconds(1000000000LL)).ok());
    const std::vector<Surfel> before = map.LiveSurfels();
    map.SetSubmapId(1);
    auto stats = map.Integrate(scan, T, Timestamp::FromNanoseconds(2000000000LL));
    ASSERT_TRUE(stats.ok());
    size_t in_submap0 = 0, in_submap1 = 0, updated0 = 0;
    for (const Surfel& s : map.LiveSurfels()) {
      if (s.submap_id == 0) {
        ++in_submap0;
        if (s.num_updates > 0) ++updated0;
      } else {
        ++in_submap1;
      }
    }
    if (only_current) {
      EXPECT_EQ(stats->num_active, 0);
      EXPECT_EQ(in_submap0, before.size());
      EXPECT_EQ(updated0, 0u);
      EXPECT_GT(in_submap1, before.size() * 9 / 10);  // the place mapped again, in submap 1
    } else {
      EXPECT_GT(stats->num_active, 100000);
      EXPECT_GT(updated0, before.size() / 2);  // SuMa's behaviour: the old surfels absorb it
      EXPECT_LT(in_submap1, before.size() / 3);
    }
  }
}

TEST(SurfelMapTest, DynamicObjectSurfelsAreDropped) {
  Scene scene;
  SurfelMap map;
  const RangeProjection& proj = map.renderer().projection();
  std::mt19937 rng(5);
  VertexNormalMap scan;
  auto box_surfels = [&] {
    int n = 0;
    for (uint32_t id = 0; id < map.surfels().size(); ++id) {
      if (!map.IsAlive(id)) continue;
      const Eigen::Vector3d p = map.surfels()[id].position.cast<double>();
      if ((p.array() > scene.box_min.array() - 0.05).all() &&
          (p.array() < scene.box_max.array() + 0.05).all() && p.z() > -1.6) {
        ++n;
      }
    }
    return n;
  };
  scene.with_box = true;
  for (int f = 0; f < 2; ++f) {
    const Eigen::Isometry3d T = PoseAt(0.2 * f);
    proj.ComputeVertexNormalMap(SimulateScan(scene, proj, T, 0.01, &rng), &scan);
    ASSERT_TRUE(map.Integrate(scan, T, Timestamp::FromNanoseconds(f + 1)).ok());
  }
  const int before = box_surfels();
  EXPECT_GT(before, 1000);
  scene.with_box = false;  // the object drives away: rays now pass through its surfels
  int conflicts = 0;
  for (int f = 2; f < 6; ++f) {
    const Eigen::Isometry3d T = PoseAt(0.2 * f);
    proj.ComputeVertexNormalMap(SimulateScan(scene, proj, T, 0.01, &rng), &scan);
    auto s = map.Integrate(scan, T, Timestamp::FromNanoseconds(f + 1));
    ASSERT_TRUE(s.ok());
    conflicts += s->num_conflicts;
  }
  EXPECT_GT(conflicts, before / 2);
  EXPECT_LT(box_surfels(), before / 20) << "before " << before;
}

TEST(SurfelMapTest, NeverConfirmedSurfelsExpireConfirmedOnesStay) {
  const Scene scene;
  std::mt19937 rng(8);
  VertexNormalMap scan, empty;
  SurfelMap probe;
  const RangeProjection& proj = probe.renderer().projection();
  proj.ComputeVertexNormalMap(SimulateScan(scene, proj, PoseAt(0.0), 0.01, &rng), &scan);
  empty.Reset(proj.rows(), proj.cols());
  for (bool confirm : {false, true}) {
    SurfelMap map;
    int f = 0;
    ASSERT_TRUE(map.Integrate(scan, PoseAt(0.0), Timestamp::FromNanoseconds(++f)).ok());
    if (confirm) {
      ASSERT_TRUE(map.Integrate(scan, PoseAt(0.0), Timestamp::FromNanoseconds(++f)).ok());
    }
    const size_t n = map.size();
    ASSERT_GT(n, 100000u);
    for (int k = 0; k < 4; ++k) {
      auto s = map.Integrate(empty, PoseAt(0.0), Timestamp::FromNanoseconds(++f));
      ASSERT_TRUE(s.ok());
      EXPECT_EQ(s->num_created, 0);
    }
    if (confirm) {
      EXPECT_GT(map.size(), n * 9 / 10);  // confirmed once: l > 0, kept while unseen
    } else {
      EXPECT_EQ(map.size(), 0u);  // seen once, never confirmed: gone after unstable_age_frames
    }
  }
}

TEST(SurfelMapTest, SelectActiveMatchesBruteForce) {
  SurfelMapOptions o;
  o.index_cell_size_m = 3.0;
  auto map = SurfelMap::Create(o);
  ASSERT_TRUE(map.ok());
  std::vector<Surfel> surfels = internal::MakeStreetSurfels(20000, 9, 50.0f);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> conf(-2.f, 2.f);
  for (auto& s : surfels) s.confidence = conf(rng);
  ASSERT_TRUE(map->AddSurfels(surfels).ok());
  // Remove some so that the index sees erasures too, and move a submap.
  for (auto& s : surfels) s.submap_id = 0;
  std::vector<uint32_t> ids;
  std::uniform_real_distribution<double> pos(-50, 50);
  for (int q = 0; q < 20; ++q) {
    const Eigen::Vector3d c(pos(rng), pos(rng) * 0.2, pos(rng) * 0.05);
    const double radius = 2.0 + std::abs(pos(rng)) * 0.6;
    const float min_conf = q % 2 == 0 ? -std::numeric_limits<float>::infinity() : 0.5f;
    map->SelectActive(c, radius, min_conf, &ids);
    // The non-const overload filters with the map's threads: the const one's ids, in its order.
    std::vector<uint32_t> serial;
    std::as_const(*map).SelectActive(c, radius, min_conf, &serial);
    EXPECT_EQ(ids, serial) << "query " << q;
    std::set<uint32_t> got(ids.begin(), ids.end());
    EXPECT_EQ(got.size(), ids.size());
    std::set<uint32_t> want;
    for (uint32_t id = 0; id < map->surfels().size(); ++id) {
      const Surfel& s = map->surfels()[id];
      if (map->IsAlive(id) && (s.position.cast<double>() - c).norm() <= radius - 1e-4 &&
          s.confidence > min_conf) {
        want.insert(id);
      }
    }
    for (uint32_t id : want) EXPECT_TRUE(got.count(id)) << "query " << q << " id " << id;
    for (uint32_t id : got) {
      EXPECT_LE((map->surfels()[id].position.cast<double>() - c).norm(), radius + 1e-4);
    }
  }
  // Every surfel a candidate (above the threshold of the threaded filter), half of them kept.
  std::vector<uint32_t> serial;
  map->SelectActive(Eigen::Vector3d::Zero(), 500.0, 0.0f, &ids);
  std::as_const(*map).SelectActive(Eigen::Vector3d::Zero(), 500.0, 0.0f, &serial);
  EXPECT_GT(ids.size(), 5000u);
  EXPECT_LT(ids.size(), 15000u);
  EXPECT_EQ(ids, serial);
  // After moving every surfel by +100 m in x, the old neighbourhood is empty and the new one full.
  EXPECT_EQ(map->TransformSubmap(0, Eigen::Isometry3d(Eigen::Translation3d(100, 0, 0))),
            surfels.size());
  map->SelectActive(Eigen::Vector3d(0, 0, 0), 30.0, -1e9f, &ids);
  EXPECT_TRUE(ids.empty());
  map->SelectActive(Eigen::Vector3d(100, 0, 0), 30.0, -1e9f, &ids);
  EXPECT_GT(ids.size(), 1000u);
}

TEST(SurfelMapTest, SaveLoadRoundTripAndCorruptFiles) {
  SurfelMap map;
  map.SetSubmapId(7);
  std::vector<Surfel> surfels = internal::MakeStreetSurfels(5000, 2);
  for (size_t i = 0; i < surfels.size(); ++i) {
    surfels[i].created_ns = static_cast<int64_t>(i) * 1000;
    surfels[i].submap_id = static_cast<int32_t>(i % 3);
    surfels[i].num_updates = static_cast<int32_t>(i % 11);
  }
  ASSERT_TRUE(map.AddSurfels(surfels).ok());
  const auto dir = testing::MakeTempDir("surfel_map_io");
  const std::string path = (dir / "map.surfels").string();
  ASSERT_TRUE(map.Save(path).ok());
  SurfelMap loaded;
  ASSERT_TRUE(loaded.Load(path).ok());
  ASSERT_EQ(loaded.size(), surfels.size());
  EXPECT_EQ(loaded.submap_id(), 7);
  const std::vector<Surfel> back = loaded.LiveSurfels();
  for (size_t i = 0; i < surfels.size(); ++i) {
    EXPECT_EQ(back[i].position, surfels[i].position);
    EXPECT_EQ(back[i].normal, surfels[i].normal);
    EXPECT_EQ(back[i].radius, surfels[i].radius);
    EXPECT_EQ(back[i].confidence, surfels[i].confidence);
    EXPECT_EQ(back[i].created_ns, surfels[i].created_ns);
    EXPECT_EQ(back[i].submap_id, surfels[i].submap_id);
    EXPECT_EQ(back[i].num_updates, surfels[i].num_updates);
  }
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto write = [&](const std::string& name, const std::string& content) {
    const std::string p = (dir / name).string();
    std::ofstream(p, std::ios::binary) << content;
    return p;
  };
  // Each corruption is reported as DataLoss and leaves the map as it was.
  std::string flipped = bytes;
  flipped[100] ^= 0x10;
  std::string bad_magic = bytes;
  bad_magic[0] = 'X';
  std::string bad_version = bytes;
  bad_version[8] = 9;
  for (const auto& [name, content] : std::vector<std::pair<std::string, std::string>>{
           {"flipped", flipped},
           {"truncated", bytes.substr(0, bytes.size() - 70)},
           {"short", bytes.substr(0, 10)},
           {"magic", bad_magic},
           {"version", bad_version},
           {"trailing", bytes + "x"}}) {
    const Status s = loaded.Load(write(name, content));
    EXPECT_EQ(s.code(), StatusCode::kDataLoss) << name << ": " << s.ToString();
    EXPECT_EQ(loaded.size(), surfels.size()) << name;
  }
  EXPECT_EQ(loaded.Load((dir / "missing").string()).code(), StatusCode::kNotFound);
  std::filesystem::remove_all(dir);
}

TEST(SurfelMapTest, RejectsBadInput) {
  SurfelMapOptions o;
  o.p_stable = 0.4;
  auto bad = SurfelMap::Create(o);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("p_stable"), std::string::npos);
  SurfelMap map;
  VertexNormalMap small;
  small.Reset(4, 4);
  EXPECT_EQ(map.Integrate(small, Eigen::Isometry3d::Identity(), Timestamp()).status().code(),
            StatusCode::kInvalidArgument);
  Surfel s;
  s.radius = -1.0f;
  EXPECT_FALSE(map.AddSurfels({s}).ok());
  EXPECT_EQ(map.size(), 0u);
  EXPECT_GT(map.MemoryBytes(), 0u);
}

}  // namespace
}  // namespace slam_mms
