// IntegrationStage (step 7 of Localizer::ProcessScan and the submap life cycle): a submap cut every
// WT (the cut scan leaves the old submap and is the new one's reference, with the reckon pose and
// covariance), the scan fused into the surfel map and the submap's cloud at its pose, and, with
// per-submap surfels, old submaps leaving the live map (the stable surfels archived, following
// their submap when it moves).
#include "pipeline/integration_stage.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace slam_mms::internal {
namespace {

constexpr int64_t kT0Ns = 1'317'000'000'000'000'000;
using CloudKind = SubmapSource::CloudKind;

Eigen::Isometry3d Forward(double x_m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().x() = x_m;
  return T;
}

Scan MakeScan(int k) {
  Scan scan;
  scan.index = 100 + k;
  scan.stamp_start = Timestamp::FromNanoseconds(kT0Ns + k * 100'000'000);
  scan.stamp_end = scan.stamp_start;
  return scan;
}

class IntegrationStageTest : public ::testing::Test {
 protected:
  void SetUp() override {
    options_.num_threads = 1;
    options_.submap_duration_s = 0.35;  // every 4th scan of 10 Hz starts a submap
    map_ = SurfelMap::Create(options_.surfels, 1).value();
  }
  IntegrationStage Make() const {
    auto stage = IntegrationStage::Create(options_, Eigen::Isometry3d::Identity());
    EXPECT_TRUE(stage.ok()) << stage.status().ToString();
    return std::move(stage).value();
  }

  Localizer::Options options_;
  SurfelMap map_;
};

TEST_F(IntegrationStageTest, TheScanAfterWtLeavesItsSubmapAndStartsTheNext) {
  IntegrationStage stage = Make();
  const Eigen::Isometry3d T_world_submap0 = Forward(50.0);
  stage.StartSubmap(T_world_submap0, MakeScan(0).stamp_start, MakeScan(0).index,
                    Eigen::Isometry3d::Identity(), Matrix6d::Identity(), &map_);
  EXPECT_EQ(map_.submap_id(), 0);
  for (int k = 0; k <= 4; ++k) {
    ScanStep step;
    step.is_reference = k == 0;
    step.T_world_submap = T_world_submap0;
    step.T_submap_cur = Forward(0.5 * k);
    LocalizationResult res;
    res.cov_T_world_body = Matrix6d::Identity() * (k + 1);
    stage.Record(MakeScan(k), step, &res);
    EXPECT_EQ(res.submap_id, 0);
    EXPECT_TRUE(res.T_world_body.isApprox(Forward(50.0 + 0.5 * k)));
    EXPECT_EQ(stage.CutDue(MakeScan(k), step), k == 4) << k;
    if (k == 4) stage.Cut(MakeScan(k), step, res.cov_T_world_body, &map_);
  }
  const std::vector<SubmapRecord>& submaps = stage.store().submaps();
  ASSERT_EQ(submaps.size(), 2u);
  const SubmapRecord& old = submaps[0];
  EXPECT_TRUE(old.finished);
  EXPECT_EQ(old.scan_indices, (std::vector<int64_t>{100, 101, 102, 103}));
  EXPECT_EQ(old.T_submap_scan.size(), 4u);
  EXPECT_EQ(old.cov_submap_scan.size(), 4u);
  EXPECT_EQ(old.end, MakeScan(3).stamp_start);
  const SubmapRecord& cur = submaps[1];
  EXPECT_EQ(cur.id, 1);
  EXPECT_FALSE(cur.finished);
  EXPECT_EQ(cur.scan_indices, (std::vector<int64_t>{104}));
  EXPECT_EQ(cur.start, MakeScan(4).stamp_start);
  EXPECT_TRUE(cur.T_world_submap.isApprox(Forward(52.0)));
  EXPECT_TRUE(cur.T_prev_this.isApprox(Forward(2.0)));
  EXPECT_EQ(cur.cov_prev_this, Matrix6d::Identity() * 5.0);
  EXPECT_EQ(map_.submap_id(), 1);
}

TEST_F(IntegrationStageTest, TheScanIsFusedIntoTheMapAndTheSubmapCloudAtItsPose) {
  IntegrationStage stage = Make();
  stage.StartSubmap(Forward(5.0), MakeScan(0).stamp_start, MakeScan(0).index,
                    Eigen::Isometry3d::Identity(), Matrix6d::Identity(), &map_);
  // A wall 10 m ahead of the LiDAR, seen at 1 m into the submap.
  DeskewedScan scan;
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 20; ++j) {
      scan.cloud.Add(Eigen::Vector3f(10.0f, -2.0f + 0.1f * i, -1.0f + 0.1f * j));
    }
  }
  const RangeProjection projection =
      RangeProjection::Create(options_.surfels.renderer.projection).value();
  projection.ComputeVertexNormalMap(scan.cloud, &scan.vnm);
  ScanStep step;
  step.T_world_submap = Forward(5.0);
  step.T_submap_cur = Forward(1.0);
  LocalizationResult res;
  ASSERT_TRUE(stage.Integrate(MakeScan(0), scan, step, &map_, &res).ok());
  EXPECT_GT(res.num_surfels, 0u);
  EXPECT_EQ(res.num_surfels, map_.size());
  for (const Surfel& s : map_.LiveSurfels()) {
    EXPECT_EQ(s.submap_id, 0);
    EXPECT_NEAR(s.position.x(), 16.0f, 0.05f);  // world: 5 + 1 + 10
  }
  stage.CloseCurrentSubmap();
  MapPointStamps stamps;
  auto cloud = stage.store().SubmapCloud(0, CloudKind::kMap, &stamps);
  ASSERT_TRUE(cloud.ok()) << cloud.status().ToString();
  ASSERT_FALSE(cloud->empty());
  for (const Eigen::Vector3f& p : cloud->points()) {
    EXPECT_NEAR(p.x(), 11.0f, options_.map_voxel_m);  // submap frame: 1 + 10
  }
  ASSERT_EQ(stamps.size(), cloud->size());
  for (int64_t index : stamps.scan_index) EXPECT_EQ(index, MakeScan(0).index);
}

TEST_F(IntegrationStageTest, SubmapsTwoBehindLeaveTheMapAndTheirStableSurfelsFollowTheirPose) {
  options_.per_submap_surfels = true;
  options_.archive_surfels = true;
  IntegrationStage stage = Make();
  const float threshold = static_cast<float>(options_.surfels.confidence_threshold);
  std::vector<Surfel> surfels(2);
  for (Surfel& s : surfels) {
    s.position = Eigen::Vector3f(10.0f, 0.0f, 0.0f);
    s.radius = 0.1f;
    s.submap_id = 0;
  }
  surfels[0].confidence = threshold + 1.0f;  // stable: archived
  surfels[1].confidence = threshold - 1.0f;  // not: dropped
  for (int id = 0; id < 3; ++id) {
    stage.StartSubmap(Forward(10.0 * id), MakeScan(4 * id).stamp_start, MakeScan(4 * id).index,
                      Eigen::Isometry3d::Identity(), Matrix6d::Identity(), &map_);
    if (id == 0) ASSERT_TRUE(map_.AddSurfels(surfels).ok());
    if (id == 1) EXPECT_EQ(map_.size(), 2u);  // submap 0 is one behind: still live
  }
  EXPECT_EQ(map_.size(), 0u);
  ASSERT_EQ(stage.archived_surfels().size(), 1u);
  ASSERT_EQ(stage.archived_surfels().at(0).size(), 1u);
  EXPECT_EQ(stage.archived_surfels().at(0)[0].confidence, surfels[0].confidence);
  // Submap 0 moves 3 m: its archived surfel and its record follow.
  ASSERT_TRUE(stage.SetSubmapPose(0, Forward(3.0), &map_).ok());
  EXPECT_NEAR(stage.archived_surfels().at(0)[0].position.x(), 13.0f, 1e-5f);
  EXPECT_TRUE(stage.store().submaps()[0].T_world_submap.isApprox(Forward(3.0)));
  EXPECT_FALSE(stage.SetSubmapPose(9, Forward(3.0), &map_).ok());
}

}  // namespace
}  // namespace slam_mms::internal
