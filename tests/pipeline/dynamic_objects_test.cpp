// DynamicObjectFilter on ray-cast range images: a street (ground, a facade) with a car that moved
// between the model and the scan.
#include "pipeline/dynamic_objects.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace slam_mms::internal {
namespace {

constexpr float kGroundZ = -1.73f;

struct Box {
  Eigen::Vector3f lo, hi;
};

// Nearest hit along a unit ray from the origin: ground plane, facade at y = 8, optional box.
bool Cast(const Eigen::Vector3f& d, const Box* car, Eigen::Vector3f* hit) {
  float best = std::numeric_limits<float>::infinity();
  if (d.z() < -1e-4f) best = std::min(best, kGroundZ / d.z());
  if (d.y() > 1e-4f) {
    const float t = 8.0f / d.y();
    if ((t * d).z() < 6.0f) best = std::min(best, t);
  }
  if (car != nullptr) {
    float t0 = 0.0f;
    float t1 = std::numeric_limits<float>::infinity();
    bool ok = true;
    for (int a = 0; a < 3 && ok; ++a) {
      if (std::abs(d[a]) < 1e-9f) {
        ok = 0.0f >= car->lo[a] && 0.0f <= car->hi[a];
        continue;
      }
      float ta = car->lo[a] / d[a];
      float tb = car->hi[a] / d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      ok = t0 <= t1;
    }
    if (ok && t0 > 0.0f) best = std::min(best, t0);
  }
  if (!(best < 80.0f)) return false;
  *hit = best * d;
  return true;
}

// The range image of the scene, offset by `shift` (a sensor pose error), normals computed.
VertexNormalMap Render(const RangeProjection& proj, const Box* car,
                       const Eigen::Vector3f& shift = Eigen::Vector3f::Zero()) {
  PointCloud cloud;
  for (int r = 0; r < proj.rows(); ++r) {
    for (int c = 0; c < proj.cols(); ++c) {
      Eigen::Vector3f p;
      if (Cast(proj.RayDirection(r, c), car, &p)) cloud.Add(p + shift);
    }
  }
  VertexNormalMap vnm;
  proj.ComputeVertexMap(cloud, &vnm);
  proj.ComputeNormals(&vnm);
  return vnm;
}

class DynamicObjectsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    RangeProjectionOptions po;
    po.cols = 1024;
    proj_ = *RangeProjection::Create(po);
    surfels_.resize(static_cast<size_t>(po.rows * po.cols) * 2);  // model index = point index
  }
  DynamicObjectFilter Filter() const { return DynamicObjectFilter(options_, proj_, 2.0, 30.0); }
  static Box Car(float x0) { return {{x0, -1.0f, kGroundZ}, {x0 + 4.2f, 1.0f, -0.3f}}; }
  // Pixels whose scan vertex lies on the car (the scan's car at x0).
  static int CountCarPixels(const VertexNormalMap& scan, const std::vector<uint8_t>* mask, float x0,
                            bool on_car) {
    int n = 0;
    for (int i = 0; i < scan.size(); ++i) {
      if (!scan.HasVertex(i)) continue;
      const Eigen::Vector3f& p = scan.vertex[static_cast<size_t>(i)];
      const bool car = p.x() > x0 - 0.05f && p.x() < x0 + 4.25f && std::abs(p.y()) < 1.05f &&
                       p.z() > kGroundZ + 0.05f;
      if (car != on_car) continue;
      if (mask == nullptr || (*mask)[static_cast<size_t>(i)]) ++n;
    }
    return n;
  }

  RangeProjection proj_;
  DynamicObjectOptions options_;
  std::vector<Surfel> surfels_;
  const Eigen::Vector3f up_ = Eigen::Vector3f::UnitZ();
  const int64_t all_ = std::numeric_limits<int64_t>::min();
};

TEST_F(DynamicObjectsTest, CarThatMovedAwayIsMaskedAndNothingElse) {
  const Box old_car = Car(6.0f);
  const Box new_car = Car(6.5f);  // moved 0.5 m away from the sensor
  const VertexNormalMap model = Render(proj_, &old_car);
  VertexNormalMap scan = Render(proj_, &new_car);
  DynamicObjectFilter f = Filter();
  const DynamicObjectStats st = f.Detect(scan, model, up_, surfels_, all_);
  EXPECT_EQ(st.num_moving, 1);
  const int car = CountCarPixels(scan, nullptr, 6.5f, true);
  const int car_masked = CountCarPixels(scan, &f.mask(), 6.5f, true);
  ASSERT_GT(car, 200);
  EXPECT_GT(car_masked, 0.9 * car) << car_masked << " of " << car;
  // Precision: at most a few ground pixels at the car's foot (their normals straddle the
  // depth jump), nothing on the facade.
  const int static_masked = CountCarPixels(scan, &f.mask(), 6.5f, false);
  EXPECT_LT(static_masked, 0.05 * car_masked) << static_masked << " static pixels masked";
  for (int i = 0; i < scan.size(); ++i) {
    if (f.mask()[static_cast<size_t>(i)]) {
      EXPECT_LT(scan.vertex[static_cast<size_t>(i)].y(), 7.9f) << "facade pixel " << i;
    }
  }
  EXPECT_FALSE(f.seen_through().empty()) << "the old car's surfels were seen through";

  // Apply and MaskPoints remove exactly what the mask says.
  const int before = scan.CountVertices();
  f.Apply(&scan);
  EXPECT_EQ(before - scan.CountVertices(), st.num_masked_pixels);
  PointCloud pts;
  pts.Add(Eigen::Vector3f(6.5f, 0.0f, -1.0f));  // on the car's rear face
  pts.Add(Eigen::Vector3f(10.0f, 8.0f, 1.0f));  // on the facade
  EXPECT_EQ(f.MaskPoints(&pts), 1u);
  EXPECT_FALSE(pts.points()[0].allFinite());
  EXPECT_TRUE(pts.points()[1].allFinite());
}

TEST_F(DynamicObjectsTest, CarThatCameCloserIsMasked) {
  const Box old_car = Car(6.5f);
  const Box new_car = Car(6.0f);
  DynamicObjectFilter f = Filter();
  const DynamicObjectStats st =
      f.Detect(Render(proj_, &new_car), Render(proj_, &old_car), up_, surfels_, all_);
  EXPECT_EQ(st.num_moving, 1);
  EXPECT_TRUE(f.seen_through().empty()) << "a car in front of its old place sees through nothing";
}

TEST_F(DynamicObjectsTest, StaticSceneAndSmallPoseErrorsFlagNothing) {
  const Box car = Car(6.0f);
  const VertexNormalMap model = Render(proj_, &car);
  DynamicObjectFilter f = Filter();
  EXPECT_EQ(f.Detect(Render(proj_, &car), model, up_, surfels_, all_).num_moving, 0);
  // A 4 cm prediction error moves everything alike: below the threshold, nothing is moving.
  EXPECT_EQ(f.Detect(Render(proj_, &car, Eigen::Vector3f(-0.04f, 0.02f, 0.0f)), model, up_,
                     surfels_, all_)
                .num_moving,
            0);
}

TEST_F(DynamicObjectsTest, OldModelSurfelsAndDisabledFilterJudgeNothing) {
  const Box old_car = Car(6.0f);
  const Box new_car = Car(6.5f);
  const VertexNormalMap model = Render(proj_, &old_car);
  const VertexNormalMap scan = Render(proj_, &new_car);
  DynamicObjectFilter f = Filter();
  // Every surfel created at 0 ns, before the travel cut-off: the map there may have drifted.
  EXPECT_EQ(f.Detect(scan, model, up_, surfels_, 1).num_moving, 0);
  options_.enabled = false;
  DynamicObjectFilter off = Filter();
  EXPECT_EQ(off.Detect(scan, model, up_, surfels_, all_).num_moving, 0);
}

TEST(DynamicObjectOptionsTest, ValidateNamesTheField) {
  DynamicObjectOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.min_outlier_fraction = 0.0;
  const Status s = o.Validate();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("DynamicObjectOptions::min_outlier_fraction"), std::string::npos)
      << s.message();
  o = DynamicObjectOptions();
  o.max_model_travel_m = -1.0;
  EXPECT_NE(o.Validate().message().find("max_model_travel_m"), std::string::npos);
}

TEST(TravelHistoryTest, StampBeforeATravelledDistance) {
  TravelHistory h;
  for (int k = 0; k <= 10; ++k) h.Add(k * 100, Eigen::Vector3d(k * 1.0, 0.0, 0.0), 5.0);
  EXPECT_EQ(h.StampBefore(5.0), 500);  // at x = 5, 5 m before x = 10
  EXPECT_EQ(h.StampBefore(2.5), 700);
  EXPECT_EQ(h.StampBefore(50.0), std::numeric_limits<int64_t>::min());
}

}  // namespace
}  // namespace slam_mms::internal
