#include "surfel/cpu_surfel_renderer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "surfel/synthetic_surfels.hpp"

namespace slam_mms {
namespace {

SurfelRendererOptions SmallOptions() {
  SurfelRendererOptions o;
  o.projection.rows = 16;
  o.projection.cols = 256;
  return o;
}

// The image definition of surfel_renderer.hpp, evaluated pixel by pixel over all surfels.
VertexNormalMap BruteForce(const RangeProjection& proj, double min_facing_cos,
                           const std::vector<Surfel>& surfels, const Eigen::Isometry3d& T_ws) {
  VertexNormalMap m;
  m.Reset(proj.rows(), proj.cols());
  const Eigen::Isometry3d T_sw = T_ws.inverse();
  const Eigen::Matrix3f R = T_sw.linear().cast<float>();
  const Eigen::Vector3f t = T_sw.translation().cast<float>();
  const float min_r = static_cast<float>(proj.options().min_range_m);
  const float max_r = static_cast<float>(proj.options().max_range_m);
  for (int i = 0; i < m.size(); ++i) {
    const Eigen::Vector3f& ray = proj.ray_directions()[i];
    float best = std::numeric_limits<float>::infinity();
    for (size_t k = 0; k < surfels.size(); ++k) {
      const Surfel& s = surfels[k];
      const Eigen::Vector3f p = R * s.position + t;
      const Eigen::Vector3f n = R * s.normal;
      const float d = p.norm();
      if (d < min_r || d > max_r || s.radius >= d) continue;
      if (!(-n.dot(p) > static_cast<float>(min_facing_cos) * d)) continue;
      const float denom = n.dot(ray);
      if (!(denom < 0.0f)) continue;
      const float tt = n.dot(p) / denom;
      if ((tt * ray - p).squaredNorm() > s.radius * s.radius) continue;
      if (tt < min_r || tt > max_r || !(tt < best)) continue;
      best = tt;
      m.vertex[i] = tt * ray;
      m.normal[i] = n;
      m.range[i] = tt;
      m.index[i] = static_cast<int32_t>(k);
    }
  }
  return m;
}

TEST(CpuSurfelRendererTest, MatchesBruteForceOracle) {
  for (int threads : {1, 2, 3}) {
    auto renderer = CpuSurfelRenderer::Create(SmallOptions(), threads);
    ASSERT_TRUE(renderer.ok()) << renderer.status().ToString();
    const auto surfels = internal::MakeStreetSurfels(3000, 7, 30.0f);
    // Larger discs so they cover the small image's big pixels.
    std::vector<Surfel> big = surfels;
    for (auto& s : big) s.radius *= 8.0f;
    Eigen::Isometry3d T_ws = Eigen::Isometry3d::Identity();
    T_ws.translation() = Eigen::Vector3d(1.5, -0.7, 0.2);
    T_ws.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    VertexNormalMap img;
    ASSERT_TRUE((*renderer)->Render(SurfelRenderInput::All(big), T_ws, &img).ok());
    const VertexNormalMap ref = BruteForce((*renderer)->projection(), 0.01, big, T_ws);
    int valid = 0, mismatch = 0;
    for (int i = 0; i < img.size(); ++i) {
      ASSERT_EQ(img.HasVertex(i), ref.HasVertex(i)) << "pixel " << i << " threads " << threads;
      if (!img.HasVertex(i)) continue;
      ++valid;
      EXPECT_NEAR(img.range[i], ref.range[i], 1e-4f);
      if (img.index[i] != ref.index[i]) ++mismatch;
      EXPECT_LT((img.vertex[i] - ref.vertex[i]).norm(), 1e-3f);
      EXPECT_NEAR(img.normal[i].norm(), 1.0f, 1e-4f);
    }
    EXPECT_GT(valid, img.size() / 2);
    EXPECT_LE(mismatch, valid / 200 + 1);  // only exact depth ties may pick another surfel
  }
}

// The full-size HDL-64 image of a street of surfels drawn through a shuffled id subset: the same
// bits for any number of threads (column bins are disjoint, records are rastered in draw order),
// and on sampled pixels the nearest disc of the image definition, ties to the earlier draw.
// A renderer keeps its splat records' memory between renders: a render after a larger one (more
// records per column bin, other bins) gives the image a fresh renderer gives.
TEST(CpuSurfelRendererTest, ReusedRendererGivesAFreshRenderersImage) {
  const std::vector<Surfel> surfels = internal::MakeStreetSurfels(60000, 5, 50.0f);
  std::vector<uint32_t> few;
  for (uint32_t i = 0; i < surfels.size(); i += 7) few.push_back(i);
  Eigen::Isometry3d T_a = Eigen::Isometry3d::Identity();
  T_a.translation() = Eigen::Vector3d(3.1, -0.4, 0.15);
  Eigen::Isometry3d T_b = T_a;
  T_b.linear() = Eigen::AngleAxisd(1.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  auto reused = CpuSurfelRenderer::Create(SurfelRendererOptions(), 2);
  auto fresh = CpuSurfelRenderer::Create(SurfelRendererOptions(), 2);
  ASSERT_TRUE(reused.ok() && fresh.ok());
  VertexNormalMap first, again, expected;
  ASSERT_TRUE((*reused)->Render(SurfelRenderInput::All(surfels), T_a, &first).ok());
  ASSERT_TRUE((*reused)->Render(SurfelRenderInput::Subset(surfels, few), T_b, &again).ok());
  ASSERT_TRUE((*fresh)->Render(SurfelRenderInput::Subset(surfels, few), T_b, &expected).ok());
  ASSERT_GT(expected.CountVertices(), expected.size() / 20);
  EXPECT_TRUE(again.range == expected.range);
  EXPECT_TRUE(again.index == expected.index);
  EXPECT_TRUE(again.normal == expected.normal);
}

TEST(CpuSurfelRendererTest, FullSizeImageIsIndependentOfThreadsAndMatchesOracle) {
  const std::vector<Surfel> surfels = internal::MakeStreetSurfels(60000, 5, 50.0f);
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < surfels.size(); i += 2) ids.push_back(i);
  std::mt19937 rng(4);
  std::shuffle(ids.begin(), ids.end(), rng);
  Eigen::Isometry3d T_ws = Eigen::Isometry3d::Identity();
  T_ws.translation() = Eigen::Vector3d(3.1, -0.4, 0.15);
  T_ws.linear() = Eigen::AngleAxisd(2.2, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                  Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitX()).toRotationMatrix();
  std::vector<VertexNormalMap> images;
  for (int threads : {1, 2, 3, 4}) {
    SurfelRendererOptions o;
    auto renderer = CpuSurfelRenderer::Create(o, threads);
    ASSERT_TRUE(renderer.ok());
    VertexNormalMap img;
    ASSERT_TRUE((*renderer)->Render(SurfelRenderInput::Subset(surfels, ids), T_ws, &img).ok());
    images.push_back(std::move(img));
  }
  const VertexNormalMap& img = images[0];
  ASSERT_GT(img.CountVertices(), img.size() / 8);
  for (size_t k = 1; k < images.size(); ++k) {
    EXPECT_TRUE(images[k].range == img.range) << "threads " << k + 1;
    EXPECT_TRUE(images[k].index == img.index) << "threads " << k + 1;
    EXPECT_TRUE(images[k].vertex == img.vertex) << "threads " << k + 1;
    EXPECT_TRUE(images[k].normal == img.normal) << "threads " << k + 1;
  }
  // Oracle on sampled pixels.
  CpuSurfelRenderer reference;
  const RangeProjection& proj = reference.projection();
  const Eigen::Isometry3d T_sw = T_ws.inverse();
  const Eigen::Matrix3f R = T_sw.linear().cast<float>();
  const Eigen::Vector3f t = T_sw.translation().cast<float>();
  const float min_r = static_cast<float>(proj.options().min_range_m);
  const float max_r = static_cast<float>(proj.options().max_range_m);
  // 300 pixels anywhere and 300 of the drawn ones.
  std::vector<int> drawn;
  for (int i = 0; i < img.size(); ++i) {
    if (img.HasVertex(i)) drawn.push_back(i);
  }
  std::uniform_int_distribution<int> pixel(0, img.size() - 1);
  std::uniform_int_distribution<size_t> drawn_pixel(0, drawn.size() - 1);
  int valid = 0, index_mismatch = 0;
  for (int q = 0; q < 600; ++q) {
    const int i = q % 2 == 0 ? pixel(rng) : drawn[drawn_pixel(rng)];
    const Eigen::Vector3f& ray = proj.ray_directions()[i];
    float best = std::numeric_limits<float>::infinity();
    int32_t best_id = -1;
    for (uint32_t id : ids) {
      const Surfel& s = surfels[id];
      const Eigen::Vector3f p = R * s.position + t;
      const Eigen::Vector3f n = R * s.normal;
      const float d = p.norm();
      if (d < min_r || d > max_r || s.radius >= d || !(-n.dot(p) > 0.01f * d)) continue;
      const float denom = n.dot(ray);
      if (!(denom < 0.0f)) continue;
      const float tt = n.dot(p) / denom;
      if ((tt * ray - p).squaredNorm() > s.radius * s.radius) continue;
      if (tt < min_r || tt > max_r || !(tt < best)) continue;
      best = tt;
      best_id = static_cast<int32_t>(id);
    }
    ASSERT_EQ(img.HasVertex(i), best_id >= 0) << "pixel " << i;
    if (best_id < 0) continue;
    ++valid;
    EXPECT_NEAR(img.range[i], best, 1e-4f * best) << "pixel " << i;
    if (img.index[i] != best_id) ++index_mismatch;
  }
  EXPECT_GT(valid, 320);
  EXPECT_LE(index_mismatch, valid / 200 + 1);  // only exact depth ties may pick another surfel
}

TEST(CpuSurfelRendererTest, DiscInFrontGivesPlaneAndRespectsIdsAndFacing) {
  CpuSurfelRenderer renderer;
  std::vector<Surfel> surfels(3);
  surfels[0].position = {10.f, 0.f, 0.f};
  surfels[0].normal = {-1.f, 0.f, 0.f};
  surfels[0].radius = 0.5f;
  surfels[1] = surfels[0];
  surfels[1].position = {8.f, 0.f, 0.f};
  surfels[1].normal = {1.f, 0.f, 0.f};  // faces away: never drawn
  surfels[2] = surfels[0];
  surfels[2].position = {20.f, 0.f, 0.f};  // behind surfel 0
  surfels[2].radius = 1.5f;
  VertexNormalMap img;
  ASSERT_TRUE(
      renderer.Render(SurfelRenderInput::All(surfels), Eigen::Isometry3d::Identity(), &img).ok());
  int n0 = 0, n2 = 0;
  for (int i = 0; i < img.size(); ++i) {
    if (!img.HasVertex(i)) continue;
    ASSERT_NE(img.index[i], 1);
    if (img.index[i] == 0) {
      ++n0;
      EXPECT_NEAR(img.vertex[i].x(), 10.f, 1e-4f);
      EXPECT_LE(std::hypot(img.vertex[i].y(), img.vertex[i].z()), 0.5f + 1e-4f);
      EXPECT_NEAR(img.normal[i].x(), -1.f, 1e-6f);
    } else {
      ++n2;
      EXPECT_NEAR(img.vertex[i].x(), 20.f, 1e-3f);
    }
  }
  // Disc of radius 0.5 at 10 m: angular radius 0.05 rad; pixels 0.00307 x 0.00764 rad.
  const double expected0 = M_PI * 0.05 * 0.05 / (2 * M_PI / 2048 * (28.0 * M_PI / 180 / 64));
  EXPECT_NEAR(n0, expected0, 0.15 * expected0);
  EXPECT_GT(n2, 0);
  // Subset: only surfel 2 (id 2 is reported in the index image).
  const std::vector<uint32_t> ids = {2};
  ASSERT_TRUE(
      renderer.Render(SurfelRenderInput::Subset(surfels, ids), Eigen::Isometry3d::Identity(), &img)
          .ok());
  for (int i = 0; i < img.size(); ++i) {
    if (img.HasVertex(i)) {
      EXPECT_EQ(img.index[i], 2);
    }
  }
  EXPECT_GT(img.CountVertices(), n2);
  // Bad ids are an error, not a crash.
  const std::vector<uint32_t> bad = {5};
  EXPECT_EQ(
      renderer.Render(SurfelRenderInput::Subset(surfels, bad), Eigen::Isometry3d::Identity(), &img)
          .code(),
      StatusCode::kInvalidArgument);
}

TEST(CpuSurfelRendererTest, WrapAroundTheRearSeam) {
  CpuSurfelRenderer renderer;
  std::vector<Surfel> surfels(1);
  surfels[0].position = {-10.f, 0.f, 0.f};  // straight behind: on the column 0 / cols-1 seam
  surfels[0].normal = {1.f, 0.f, 0.f};
  surfels[0].radius = 0.3f;
  VertexNormalMap img;
  ASSERT_TRUE(
      renderer.Render(SurfelRenderInput::All(surfels), Eigen::Isometry3d::Identity(), &img).ok());
  int left = 0, right = 0;
  for (int i = 0; i < img.size(); ++i) {
    if (!img.HasVertex(i)) continue;
    const int col = i % img.cols;
    if (col < 100) ++left;
    if (col > img.cols - 100) ++right;
  }
  EXPECT_GT(left, 5);
  EXPECT_NEAR(left, right, 4);
}

TEST(CpuSurfelRendererTest, RejectsBadOptions) {
  SurfelRendererOptions o;
  auto r = CpuSurfelRenderer::Create(o, 0);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("num_threads"), std::string::npos);
}

}  // namespace
}  // namespace slam_mms
