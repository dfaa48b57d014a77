// ModelRenderStage (step 3 of Localizer::ProcessScan) on hand-placed surfels (a wall ahead of the
// sensor per submap): which submaps are rendered (the current one, the previous one while the
// current is young), the minimum model size, SuMa's confidence ramp over the first 10 scans, and
// the model image being the map renderer's image of the selected surfels at the prediction.
#include "pipeline/model_render_stage.hpp"

#include <gtest/gtest.h>

#include <set>
#include <vector>

namespace slam_mms::internal {
namespace {

constexpr int64_t kT0Ns = 1'317'000'000'000'000'000;

/// A 20 x 20 wall of surfels (0.2 m apart) facing the origin at x = 10 m, in submap `submap_id`.
std::vector<Surfel> Wall(int32_t submap_id, float confidence, int count = 400) {
  std::vector<Surfel> wall;
  for (int i = 0; i < count; ++i) {
    Surfel s;
    s.position = Eigen::Vector3f(10.0f + 0.01f * static_cast<float>(submap_id),
                                 -2.0f + 0.2f * static_cast<float>(i % 20),
                                 -1.0f + 0.2f * static_cast<float>(i / 20));
    s.normal = -Eigen::Vector3f::UnitX();
    s.radius = 0.15f;
    s.confidence = confidence;
    s.submap_id = submap_id;
    wall.push_back(s);
  }
  return wall;
}

class ModelRenderStageTest : public ::testing::Test {
 protected:
  void SetUp() override {
    options_.num_threads = 1;
    options_.previous_submap_model_s = 1.0;
    options_.min_model_confidence = 0.0;
    map_ = SurfelMap::Create(options_.surfels, 1).value();
  }
  void Add(const std::vector<Surfel>& surfels) { ASSERT_TRUE(map_.AddSurfels(surfels).ok()); }

  /// Renders for a scan `seconds` into submap `id` after `num_processed` scans.
  ScanStep Render(ModelRenderStage* stage, int32_t id, double seconds, int64_t num_processed,
                  LocalizationResult* res) {
    SubmapRecord submap;
    submap.id = id;
    submap.start = Timestamp::FromNanoseconds(kT0Ns);
    Scan scan;
    scan.stamp_start = Timestamp::FromNanoseconds(kT0Ns + static_cast<int64_t>(seconds * 1e9));
    ScanStep step;
    EXPECT_TRUE(stage->Render(scan, submap, num_processed, &map_, &step, res).ok());
    return step;
  }
  std::set<int32_t> ModelSubmaps(const ModelRenderStage& stage) const {
    std::set<int32_t> ids;
    for (uint32_t id : stage.model_ids()) ids.insert(map_.surfels()[id].submap_id);
    return ids;
  }

  Localizer::Options options_;
  SurfelMap map_;
};

TEST_F(ModelRenderStageTest, TheCurrentSubmapAndWhileItIsYoungThePreviousOne) {
  for (int32_t id = 0; id < 3; ++id) Add(Wall(id, 1.0f));
  ModelRenderStage stage(options_, Eigen::Isometry3d::Identity());
  LocalizationResult res;
  ScanStep step = Render(&stage, 2, 0.5, 20, &res);
  EXPECT_EQ(res.num_model_surfels, 800u);
  EXPECT_EQ(ModelSubmaps(stage), (std::set<int32_t>{1, 2}));
  EXPECT_TRUE(step.have_model);
  step = Render(&stage, 2, 1.0, 20, &res);  // as old as previous_submap_model_s: current only
  EXPECT_EQ(res.num_model_surfels, 400u);
  EXPECT_EQ(ModelSubmaps(stage), (std::set<int32_t>{2}));
}

TEST_F(ModelRenderStageTest, FewerThanAHundredSurfelsAreNoModel) {
  Add(Wall(0, 1.0f, static_cast<int>(kMinModelSurfels) - 1));
  ModelRenderStage stage(options_, Eigen::Isometry3d::Identity());
  LocalizationResult res;
  EXPECT_FALSE(Render(&stage, 0, 0.0, 20, &res).have_model);
  EXPECT_EQ(res.num_model_surfels, kMinModelSurfels - 1);
  Add(Wall(0, 1.0f, 1));
  EXPECT_TRUE(Render(&stage, 0, 0.0, 20, &res).have_model);
  EXPECT_FALSE(Render(&stage, 7, 0.0, 20, &res).have_model);  // another submap's surfels only
  EXPECT_EQ(res.num_model_surfels, 0u);
}

TEST_F(ModelRenderStageTest, TheConfidenceThresholdRampsUpOverTheFirstTenScans) {
  Add(Wall(0, -1.0f));  // unstable: above ln(0.1 / 0.9) = -2.20, below 0
  ModelRenderStage stage(options_, Eigen::Isometry3d::Identity());
  LocalizationResult res;
  Render(&stage, 0, 0.0, 0, &res);  // threshold -2.20
  EXPECT_EQ(res.num_model_surfels, 400u);
  Render(&stage, 0, 0.0, 5, &res);  // threshold -1.10
  EXPECT_EQ(res.num_model_surfels, 400u);
  Render(&stage, 0, 0.0, 6, &res);  // threshold -0.88
  EXPECT_EQ(res.num_model_surfels, 0u);
  Render(&stage, 0, 0.0, 100, &res);  // threshold min_model_confidence = 0
  EXPECT_EQ(res.num_model_surfels, 0u);
}

TEST_F(ModelRenderStageTest, TheModelIsTheMapRenderersImageAtThePrediction) {
  Add(Wall(0, 1.0f));
  Eigen::Isometry3d T_body_lidar = Eigen::Isometry3d::Identity();
  T_body_lidar.translation() = Eigen::Vector3d(0.3, 0.0, 1.2);
  ModelRenderStage stage(options_, T_body_lidar);
  SubmapRecord submap;
  submap.start = Timestamp::FromNanoseconds(kT0Ns);
  Scan scan;
  scan.stamp_start = submap.start;
  ScanStep step;
  step.T_world_submap.translation() = Eigen::Vector3d(0.5, 0.0, 0.0);
  step.pred.T_submap.translation() = Eigen::Vector3d(1.0, 0.2, -1.2);
  LocalizationResult res;
  ASSERT_TRUE(stage.Render(scan, submap, 20, &map_, &step, &res).ok());
  ASSERT_TRUE(step.have_model);
  EXPECT_TRUE(
      step.T_world_lidar_pred.isApprox(step.T_world_submap * step.pred.T_submap * T_body_lidar));
  VertexNormalMap expected;
  ASSERT_TRUE(map_.renderer()
                  .Render(SurfelRenderInput::Subset(map_.surfels(), stage.model_ids()),
                          step.T_world_lidar_pred, &expected)
                  .ok());
  EXPECT_EQ(stage.model().vertex, expected.vertex);
  EXPECT_EQ(stage.model().index, expected.index);
  int valid = 0;
  for (int32_t i : stage.model().index) valid += i >= 0 ? 1 : 0;
  EXPECT_GT(valid, 100);  // the wall is in view
}

}  // namespace
}  // namespace slam_mms::internal
