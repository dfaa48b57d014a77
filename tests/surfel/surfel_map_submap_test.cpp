// SurfelMap::RemoveSubmap / RemoveSubmapsExcept / SubmapSizes / Compact: the removed surfels are
// exactly those of the submaps, the spatial index stays consistent (brute-force oracle), slots are
// reused, Compact gives memory back and a compacted map integrates like the original.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "slam_mms/surfel/range_projection.hpp"
#include "slam_mms/surfel/surfel_map.hpp"
#include "surfel/synthetic_surfels.hpp"

namespace slam_mms {
namespace {

// Surfels of a street, submap id = k % num_submaps.
std::vector<Surfel> StreetWithSubmaps(size_t n, int num_submaps, uint32_t seed) {
  std::vector<Surfel> s = internal::MakeStreetSurfels(n, seed, 50.0f);
  for (size_t k = 0; k < s.size(); ++k) s[k].submap_id = static_cast<int32_t>(k % num_submaps);
  return s;
}

// Every query: SelectActive == the brute-force set of live surfels within the radius.
void ExpectIndexMatchesBruteForce(const SurfelMap& map, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(-50, 50);
  std::vector<uint32_t> ids;
  for (int q = 0; q < 12; ++q) {
    const Eigen::Vector3d c(pos(rng), pos(rng) * 0.2, pos(rng) * 0.05);
    const double radius = 3.0 + std::abs(pos(rng)) * 0.6;
    map.SelectActive(c, radius, -std::numeric_limits<float>::infinity(), &ids);
    const std::set<uint32_t> got(ids.begin(), ids.end());
    ASSERT_EQ(got.size(), ids.size()) << "duplicate ids, query " << q;
    for (uint32_t id : got) {
      ASSERT_TRUE(map.IsAlive(id)) << "dead id " << id << " selected, query " << q;
      EXPECT_LE((map.surfels()[id].position.cast<double>() - c).norm(), radius + 1e-4);
    }
    for (uint32_t id = 0; id < map.surfels().size(); ++id) {
      if (!map.IsAlive(id)) continue;
      if ((map.surfels()[id].position.cast<double>() - c).norm() <= radius - 1e-4) {
        EXPECT_TRUE(got.count(id)) << "query " << q << " misses id " << id;
      }
    }
  }
}

bool SameSurfel(const Surfel& a, const Surfel& b) {
  return a.position == b.position && a.normal == b.normal && a.radius == b.radius &&
         a.confidence == b.confidence && a.submap_id == b.submap_id &&
         a.created_frame == b.created_frame && a.updated_frame == b.updated_frame &&
         a.num_updates == b.num_updates && a.created_ns == b.created_ns &&
         a.updated_ns == b.updated_ns;
}

TEST(SurfelMapSubmapTest, RemoveSubmapRemovesExactlyItsSurfelsAndKeepsOtherIds) {
  SurfelMapOptions o;
  o.index_cell_size_m = 4.0;
  auto map = SurfelMap::Create(o);
  ASSERT_TRUE(map.ok());
  const std::vector<Surfel> surfels = StreetWithSubmaps(30000, 5, 3);
  auto ids = map->AddSurfels(surfels);
  ASSERT_TRUE(ids.ok());
  const auto sizes = map->SubmapSizes();
  ASSERT_EQ(sizes.size(), 5u);
  for (const auto& [sid, count] : sizes) EXPECT_EQ(count, 6000u) << "submap " << sid;

  std::vector<Surfel> removed;
  EXPECT_EQ(map->RemoveSubmap(2, &removed), 6000u);
  EXPECT_EQ(map->RemoveSubmap(2), 0u);   // already gone
  EXPECT_EQ(map->RemoveSubmap(77), 0u);  // unknown
  ASSERT_EQ(removed.size(), 6000u);
  for (const Surfel& s : removed) EXPECT_EQ(s.submap_id, 2);
  EXPECT_EQ(map->size(), 24000u);
  for (size_t k = 0; k < surfels.size(); ++k) {
    const uint32_t id = (*ids)[k];
    if (surfels[k].submap_id == 2) {
      EXPECT_FALSE(map->IsAlive(id));
    } else {
      ASSERT_TRUE(map->IsAlive(id));
      EXPECT_TRUE(SameSurfel(map->surfels()[id], surfels[k])) << "id " << id;
    }
  }
  ExpectIndexMatchesBruteForce(*map, 11);

  // Slots are reused: adding as many surfels as were removed does not grow the slot vector.
  const size_t slots = map->surfels().size();
  ASSERT_TRUE(map->AddSurfels(removed).ok());
  EXPECT_EQ(map->surfels().size(), slots);
  EXPECT_EQ(map->size(), 30000u);
  ExpectIndexMatchesBruteForce(*map, 12);
}

TEST(SurfelMapSubmapTest, RemoveSubmapsExceptKeepsOnlyTheListed) {
  SurfelMap map;
  const std::vector<Surfel> surfels = StreetWithSubmaps(20000, 8, 4);
  ASSERT_TRUE(map.AddSurfels(surfels).ok());
  std::vector<Surfel> removed;
  EXPECT_EQ(map.RemoveSubmapsExcept({6, 1, 6, 100}, &removed), 15000u);
  const auto sizes = map.SubmapSizes();
  ASSERT_EQ(sizes.size(), 2u);
  EXPECT_EQ(sizes[0], (std::pair<int32_t, size_t>(1, 2500u)));
  EXPECT_EQ(sizes[1], (std::pair<int32_t, size_t>(6, 2500u)));
  for (const Surfel& s : removed) EXPECT_TRUE(s.submap_id != 1 && s.submap_id != 6);
  ExpectIndexMatchesBruteForce(map, 13);
  EXPECT_EQ(map.RemoveSubmapsExcept({}), 5000u);
  EXPECT_EQ(map.size(), 0u);
  EXPECT_TRUE(map.SubmapSizes().empty());
  std::vector<uint32_t> ids;
  map.SelectActive(Eigen::Vector3d::Zero(), 1000.0, -1e9f, &ids);
  EXPECT_TRUE(ids.empty());
}

TEST(SurfelMapSubmapTest, CompactRenumbersInOrderAndReleasesMemory) {
  SurfelMapOptions o;
  o.index_cell_size_m = 4.0;
  auto map = SurfelMap::Create(o);
  ASSERT_TRUE(map.ok());
  ASSERT_TRUE(map->AddSurfels(StreetWithSubmaps(60000, 6, 5)).ok());
  EXPECT_EQ(map->RemoveSubmapsExcept({4, 5}), 40000u);
  const std::vector<Surfel> live_before = map->LiveSurfels();
  const size_t bytes_before = map->MemoryBytes();
  const size_t released = map->Compact();
  EXPECT_GT(released, 0u);
  EXPECT_EQ(map->MemoryBytes(), bytes_before - released);
  // 40000 of 60000 64-byte slots freed: at least 2/3 of the slot storage comes back.
  EXPECT_GT(released, 40000u * sizeof(Surfel) * 9 / 10);
  ASSERT_EQ(map->surfels().size(), live_before.size());
  EXPECT_EQ(map->size(), live_before.size());
  for (uint32_t id = 0; id < live_before.size(); ++id) {
    ASSERT_TRUE(map->IsAlive(id));
    EXPECT_TRUE(SameSurfel(map->surfels()[id], live_before[id])) << "id " << id;
  }
  ExpectIndexMatchesBruteForce(*map, 14);
  EXPECT_EQ(map->Compact(), 0u);  // nothing more to give back
  // Still a working map: moving and removing a submap keep the index consistent.
  EXPECT_EQ(map->TransformSubmap(5, Eigen::Isometry3d(Eigen::Translation3d(0, 20, 0))), 10000u);
  ExpectIndexMatchesBruteForce(*map, 15);
  EXPECT_EQ(map->RemoveSubmap(4), 10000u);
  ExpectIndexMatchesBruteForce(*map, 16);
}

// A corridor of planes (ground, two walls, an end wall) seen from a sensor driving along x.
VertexNormalMap CorridorScan(const RangeProjection& proj, const Eigen::Isometry3d& T_ws,
                             std::mt19937* rng) {
  struct Plane {
    Eigen::Vector3d n;
    double offset;
  };
  const Plane planes[] = {{{0, 0, 1}, -1.73}, {{0, 1, 0}, 6.0}, {{0, -1, 0}, 6.0}, {{1, 0, 0}, 45}};
  std::uniform_real_distribution<float> jitter(0.05f, 0.95f);
  std::normal_distribution<double> noise(0.0, 0.02);
  PointCloud cloud;
  for (int r = 0; r < proj.rows(); ++r) {
    for (int c = 0; c < proj.cols(); ++c) {
      const Eigen::Vector3d d_s =
          proj.Unproject(c + jitter(*rng), r + jitter(*rng), 1.0f).cast<double>().normalized();
      const Eigen::Vector3d d_w = T_ws.linear() * d_s;
      double best = std::numeric_limits<double>::infinity();
      for (const Plane& p : planes) {
        const double den = p.n.dot(d_w);
        if (std::abs(den) < 1e-9) continue;
        const double t = (p.offset - p.n.dot(T_ws.translation())) / den;
        if (t > 0 && t < best) best = t;
      }
      if (best < 70.0) cloud.Add(((best + noise(*rng)) * d_s).cast<float>());
    }
  }
  VertexNormalMap m;
  proj.ComputeVertexNormalMap(cloud, &m);
  return m;
}

std::vector<std::tuple<float, float, float, float, float, int32_t>> SortedKeys(
    const std::vector<Surfel>& surfels) {
  std::vector<std::tuple<float, float, float, float, float, int32_t>> keys;
  for (const Surfel& s : surfels) {
    keys.emplace_back(s.position.x(), s.position.y(), s.position.z(), s.radius, s.confidence,
                      s.submap_id);
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

TEST(SurfelMapSubmapTest, CompactedMapIntegratesLikeTheOriginal) {
  SurfelMapOptions o;
  o.renderer.projection.rows = 32;
  o.renderer.projection.cols = 512;
  auto a = SurfelMap::Create(o);
  auto b = SurfelMap::Create(o);
  ASSERT_TRUE(a.ok() && b.ok());
  const RangeProjection& proj = a->renderer().projection();
  std::mt19937 rng(21);
  std::vector<VertexNormalMap> scans;
  std::vector<Eigen::Isometry3d> poses;
  for (int f = 0; f < 12; ++f) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(1.5 * f, 0.2, 0.0);
    poses.push_back(T);
    scans.push_back(CorridorScan(proj, T, &rng));
  }
  // Both maps see scans 0..7 in submaps 0 and 1; then submap 0 is removed from both and only `b`
  // is compacted; both integrate scans 8..11 into submap 2.
  for (int f = 0; f < 8; ++f) {
    for (SurfelMap* m : {&*a, &*b}) {
      m->SetSubmapId(f < 4 ? 0 : 1);
      ASSERT_TRUE(m->Integrate(scans[f], poses[f], Timestamp::FromNanoseconds(f)).ok());
    }
  }
  const size_t removed = a->RemoveSubmap(0);
  ASSERT_GT(removed, 1000u);
  ASSERT_EQ(b->RemoveSubmap(0), removed);
  ASSERT_EQ(a->size(), b->size());
  EXPECT_GT(b->Compact(), 0u);
  for (int f = 8; f < 12; ++f) {
    std::vector<SurfelIntegrationStats> stats;
    for (SurfelMap* m : {&*a, &*b}) {
      m->SetSubmapId(2);
      auto s = m->Integrate(scans[f], poses[f], Timestamp::FromNanoseconds(f));
      ASSERT_TRUE(s.ok()) << s.status().ToString();
      stats.push_back(*s);
    }
    EXPECT_EQ(stats[0].num_active, stats[1].num_active) << "scan " << f;
    EXPECT_EQ(stats[0].num_confirmed, stats[1].num_confirmed) << "scan " << f;
    EXPECT_EQ(stats[0].num_created, stats[1].num_created) << "scan " << f;
    EXPECT_EQ(stats[0].num_removed, stats[1].num_removed) << "scan " << f;
    EXPECT_GT(stats[0].num_confirmed, 1000) << "scan " << f;
  }
  EXPECT_EQ(a->size(), b->size());
  EXPECT_TRUE(SortedKeys(a->LiveSurfels()) == SortedKeys(b->LiveSurfels()));
}

}  // namespace
}  // namespace slam_mms
