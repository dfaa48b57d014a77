#include "pipeline/submap_store.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "testing/test_data.hpp"

namespace slam_mms::internal {
namespace {

PointCloud Cloud(int n, float offset) {
  PointCloud c;
  for (int i = 0; i < n; ++i) c.Add(Eigen::Vector3f(offset + 0.1f * i, 1.0f, -0.5f), 0.25f);
  return c;
}

MapPointStamps Stamps(int n) {
  MapPointStamps s;
  for (int i = 0; i < n; ++i) {
    s.time_ns.push_back(1000 + i);
    s.scan_index.push_back(i % 3);
  }
  return s;
}

// Starts and finishes `n` submaps, submap k with a map cloud of 10 + k points and a registration
// cloud of 5 + k.
void Fill(SubmapStore* store, int n) {
  for (int k = 0; k < n; ++k) {
    const Eigen::Isometry3d T(Eigen::Translation3d(10.0 * k, 0, 0));
    SubmapRecord& rec =
        store->Start(T, Timestamp::FromSeconds(100.0 + 5 * k), 50 * k, T, Matrix6d::Identity());
    EXPECT_EQ(rec.id, k);
    store->FinishCurrent(Cloud(10 + k, k), Stamps(10 + k), Cloud(5 + k, -k));
  }
}

TEST(SubmapStoreTest, RecordsIdsAndTheReferenceScan) {
  SubmapStore store;
  EXPECT_TRUE(store.empty());
  SubmapRecord& rec = store.Start(Eigen::Isometry3d::Identity(), Timestamp::FromSeconds(7.0), 42,
                                  Eigen::Isometry3d::Identity(), Matrix6d::Identity());
  EXPECT_EQ(rec.id, 0);
  ASSERT_EQ(rec.scan_indices.size(), 1u);
  EXPECT_EQ(rec.scan_indices[0], 42);
  EXPECT_TRUE(rec.T_submap_scan[0].isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_FALSE(rec.finished);
  store.FinishCurrent(Cloud(4, 0), Stamps(4), Cloud(2, 0));
  EXPECT_TRUE(store.current().finished);
  EXPECT_EQ(store.current().cloud_size, 4u);
  // A second finish of the same submap keeps its clouds.
  store.FinishCurrent(Cloud(9, 0), Stamps(9), Cloud(9, 0));
  EXPECT_EQ(store.current().cloud_size, 4u);
  EXPECT_EQ(store
                .Start(Eigen::Isometry3d::Identity(), Timestamp::FromSeconds(9.0), 43,
                       Eigen::Isometry3d::Identity(), Matrix6d::Identity())
                .id,
            1);
}

TEST(SubmapStoreTest, InMemoryCloudsAndPoses) {
  SubmapStore store;
  Fill(&store, 3);
  EXPECT_TRUE(store.spill_folder().empty());
  MapPointStamps stamps;
  auto map = store.SubmapCloud(1, SubmapSource::CloudKind::kMap, &stamps);
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  EXPECT_EQ(map->size(), 11u);
  EXPECT_EQ(stamps.time_ns.size(), 11u);
  auto reg = store.SubmapCloud(0, SubmapSource::CloudKind::kRegistration);
  ASSERT_TRUE(reg.ok());
  EXPECT_EQ(reg->size(), 5u);
  EXPECT_EQ(store.SubmapCloud(7, SubmapSource::CloudKind::kMap).status().code(),
            StatusCode::kNotFound);
  const Eigen::Isometry3d T(Eigen::Translation3d(1, 2, 3));
  ASSERT_TRUE(store.SetPose(2, T).ok());
  EXPECT_TRUE(store.submaps()[2].T_world_submap.isApprox(T));
  EXPECT_EQ(store.SetPose(9, T).code(), StatusCode::kNotFound);
  store.ReleaseClouds(1, /*keep_registration_cloud=*/true);
  EXPECT_EQ(store.SubmapCloud(1, SubmapSource::CloudKind::kMap)->size(), 0u);
  EXPECT_EQ(store.SubmapCloud(1, SubmapSource::CloudKind::kRegistration)->size(), 6u);
}

TEST(SubmapStoreTest, SpillsFinishedMapCloudsAndOldRegistrationCloudsAndReadsThemBack) {
  testing::ScopedTempDir dir("submap_store");
  auto created = SubmapStore::Create(dir.path);
  ASSERT_TRUE(created.ok()) << created.status().ToString();
  SubmapStore store = std::move(created).value();
  ASSERT_FALSE(store.spill_folder().empty());
  Fill(&store, 4);
  const auto& recs = store.submaps();
  for (const SubmapRecord& rec : recs) {
    EXPECT_TRUE(rec.cloud.empty()) << rec.id;  // every finished map cloud is on disk
    EXPECT_TRUE(std::filesystem::exists(rec.cloud_file)) << rec.id;
    EXPECT_EQ(rec.cloud_size, static_cast<size_t>(10 + rec.id));
  }
  // Registration clouds leave memory once two behind: 0 and 1 of 0..3.
  EXPECT_FALSE(recs[0].registration_cloud_file.empty());
  EXPECT_FALSE(recs[1].registration_cloud_file.empty());
  EXPECT_TRUE(recs[2].registration_cloud_file.empty());
  EXPECT_EQ(recs[3].registration_cloud.size(), 8u);
  MapPointStamps stamps;
  auto map = store.SubmapCloud(2, SubmapSource::CloudKind::kMap, &stamps);
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  ASSERT_EQ(map->size(), 12u);
  EXPECT_EQ(map->points()[3], Cloud(12, 2).points()[3]);
  EXPECT_EQ(stamps.time_ns, Stamps(12).time_ns);
  EXPECT_EQ(store.SubmapCloud(0, SubmapSource::CloudKind::kRegistration)->size(), 5u);
  // Released clouds take their files with them.
  const std::filesystem::path map_file = recs[0].cloud_file;
  const std::filesystem::path reg_file = recs[0].registration_cloud_file;
  store.ReleaseClouds(0, /*keep_registration_cloud=*/false);
  EXPECT_FALSE(std::filesystem::exists(map_file));
  EXPECT_FALSE(std::filesystem::exists(reg_file));
  // A corrupt spill file is an error naming the submap, not a crash or an empty cloud.
  std::filesystem::resize_file(recs[1].cloud_file, 3);
  const Status bad = store.SubmapCloud(1, SubmapSource::CloudKind::kMap).status();
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("submap 1"), std::string::npos) << bad.message();
  // The private folder goes with the store.
  const std::filesystem::path folder = store.spill_folder();
  { SubmapStore gone = std::move(store); }
  EXPECT_FALSE(std::filesystem::exists(folder));
}

TEST(SubmapStoreTest, AnUncreatableSpillFolderIsAnError) {
  testing::ScopedTempDir dir("submap_store_bad");
  const std::filesystem::path file = dir.path / "not_a_folder";
  { std::ofstream(file) << "x"; }
  EXPECT_FALSE(SubmapStore::Create(file / "sub").ok());
}

}  // namespace
}  // namespace slam_mms::internal
