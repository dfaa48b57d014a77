#include "render_egl/egl_surfel_renderer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "slam_mms/surfel/surfel_map.hpp"
#include "surfel/cpu_surfel_renderer.hpp"
#include "surfel/synthetic_surfels.hpp"

namespace slam_mms {
namespace {

// Skips (with the reason) where no EGL context can be made; the failure must be a Status.
#define REQUIRE_EGL(var, options)                                            \
  auto var##_or = EglSurfelRenderer::Create(options);                        \
  if (!var##_or.ok()) {                                                      \
    ASSERT_EQ(var##_or.status().code(), StatusCode::kUnavailable);           \
    GTEST_SKIP() << "EGL unavailable here: " << var##_or.status().message(); \
  }                                                                          \
  std::unique_ptr<EglSurfelRenderer> var = std::move(var##_or).value()

struct Comparison {
  int valid_cpu = 0, valid_egl = 0, valid_both = 0, valid_mismatch = 0;
  int range_off = 0, index_diff = 0, normal_off = 0;
};

Comparison Compare(const VertexNormalMap& a, const VertexNormalMap& b) {
  Comparison c;
  for (int i = 0; i < a.size(); ++i) {
    c.valid_cpu += a.HasVertex(i);
    c.valid_egl += b.HasVertex(i);
    if (a.HasVertex(i) != b.HasVertex(i)) ++c.valid_mismatch;
    if (!a.HasVertex(i) || !b.HasVertex(i)) continue;
    ++c.valid_both;
    if (std::abs(a.range[i] - b.range[i]) > 1e-3f) ++c.range_off;
    if (a.index[i] != b.index[i]) {
      ++c.index_diff;
    } else if (a.normal[i].dot(b.normal[i]) < 0.99999f ||
               (a.vertex[i] - b.vertex[i]).norm() > 1e-3f) {
      ++c.normal_off;
    }
  }
  return c;
}

Eigen::Isometry3d TestPose() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(3.2, -0.8, 0.4);
  T.linear() = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return T;
}

TEST(EglSurfelRendererTest, SameImagesAsCpuRenderer) {
  const SurfelRendererOptions options;
  REQUIRE_EGL(egl, options);
  auto cpu = CpuSurfelRenderer::Create(options);
  ASSERT_TRUE(cpu.ok());
  EXPECT_FALSE(egl->gl_renderer().empty());
  for (size_t n : {20000u, 100000u}) {
    const auto surfels = internal::MakeStreetSurfels(n, 11);
    VertexNormalMap img_cpu, img_egl;
    ASSERT_TRUE((*cpu)->Render(SurfelRenderInput::All(surfels), TestPose(), &img_cpu).ok());
    const Status s = egl->Render(SurfelRenderInput::All(surfels), TestPose(), &img_egl);
    ASSERT_TRUE(s.ok()) << s.ToString();
    const Comparison c = Compare(img_cpu, img_egl);
    SCOPED_TRACE(::testing::Message()
                 << "n=" << n << " valid cpu " << c.valid_cpu << " egl " << c.valid_egl
                 << " mismatch " << c.valid_mismatch << " range_off " << c.range_off
                 << " index_diff " << c.index_diff << " normal_off " << c.normal_off);
    EXPECT_GT(c.valid_cpu, img_cpu.size() / 10);
    // Same pixels valid (differences only where float rounding puts a pixel centre on a disc edge).
    EXPECT_LE(c.valid_mismatch, c.valid_cpu / 1000 + 2);
    // Same ranges and surfels.
    EXPECT_LE(c.range_off, c.valid_both / 1000 + 2);
    EXPECT_LE(c.index_diff, c.valid_both / 200 + 2);
    EXPECT_LE(c.normal_off, 0);
    std::printf("n=%zu: valid cpu %d egl %d, mismatch %d, range>1mm %d, index differs %d\n", n,
                c.valid_cpu, c.valid_egl, c.valid_mismatch, c.range_off, c.index_diff);
  }
}

TEST(EglSurfelRendererTest, SubsetIdsAndRearSeamMatchCpu) {
  const SurfelRendererOptions options;
  REQUIRE_EGL(egl, options);
  CpuSurfelRenderer cpu;
  auto surfels = internal::MakeStreetSurfels(30000, 4);
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < surfels.size(); i += 3) ids.push_back(i);
  // Pose looking backwards so the street runs across the rear seam.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(-5, 0.5, 0);
  VertexNormalMap a, b;
  ASSERT_TRUE(cpu.Render(SurfelRenderInput::Subset(surfels, ids), T, &a).ok());
  ASSERT_TRUE(egl->Render(SurfelRenderInput::Subset(surfels, ids), T, &b).ok());
  const Comparison c = Compare(a, b);
  EXPECT_GT(c.valid_cpu, 10000);
  EXPECT_LE(c.valid_mismatch, c.valid_cpu / 1000 + 2);
  EXPECT_LE(c.range_off, c.valid_both / 1000 + 2);
  for (int i = 0; i < b.size(); ++i) {
    if (b.HasVertex(i)) {
      ASSERT_EQ(b.index[i] % 3, 0) << "index must be the surfel id";
    }
  }
  // Both sides of the seam are drawn.
  int seam_left = 0, seam_right = 0;
  for (int r = 0; r < b.rows; ++r) {
    seam_left += b.HasVertex(b.PixelIndex(r, 0));
    seam_right += b.HasVertex(b.PixelIndex(r, b.cols - 1));
  }
  EXPECT_GT(seam_left, 5);
  EXPECT_GT(seam_right, 5);
  // Empty input: an all-invalid image.
  ASSERT_TRUE(egl->Render(SurfelRenderInput{}, T, &b).ok());
  EXPECT_EQ(b.CountVertices(), 0);
}

// The host side split over threads (surfels gathered into the mapped buffer, images unpacked)
// gives the same image, bit for bit, as one thread, for a subset with ids and for all surfels,
// also when the buffer grows between renders; a thread count outside [1, 64] is refused.
TEST(EglSurfelRendererTest, SameImageForAnyThreadCount) {
  const SurfelRendererOptions options;
  REQUIRE_EGL(one, options);
  auto three = EglSurfelRenderer::Create(options, 3);
  ASSERT_TRUE(three.ok()) << three.status().ToString();
  const auto surfels = internal::MakeStreetSurfels(60000, 7);
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < surfels.size(); i += 2) ids.push_back(i);
  for (const SurfelRenderInput& input :
       {SurfelRenderInput::Subset(surfels, ids), SurfelRenderInput::All(surfels)}) {
    VertexNormalMap a, b;
    ASSERT_TRUE(one->Render(input, TestPose(), &a).ok());
    ASSERT_TRUE((*three)->Render(input, TestPose(), &b).ok());
    ASSERT_GT(a.CountVertices(), a.size() / 10);
    ASSERT_EQ(a.size(), b.size());
    for (int i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a.index[i], b.index[i]) << i;
      ASSERT_EQ(a.range[i], b.range[i]) << i;
      ASSERT_EQ(a.vertex[i], b.vertex[i]) << i;
      ASSERT_EQ(a.normal[i], b.normal[i]) << i;
    }
  }
  for (int bad : {0, 65}) {
    auto r = EglSurfelRenderer::Create(options, bad);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(r.status().message().find("num_threads"), std::string::npos);
  }
}

TEST(EglSurfelRendererTest, ImpossibleImageSizeIsAStatusNotACrash) {
  SurfelRendererOptions options;
  options.projection.rows = 4;
  options.projection.cols = 1 << 20;  // wider than any GL_MAX_TEXTURE_SIZE
  auto r = EglSurfelRenderer::Create(options);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kUnavailable);
  EXPECT_FALSE(r.status().message().empty());
}

TEST(EglSurfelRendererTest, SurfelMapIntegratesTheSameWithEitherRenderer) {
  const SurfelRendererOptions options;
  REQUIRE_EGL(egl, options);
  // "Scans": images of a synthetic street rendered at two poses.
  CpuSurfelRenderer cpu;
  const auto street = internal::MakeStreetSurfels(60000, 21);
  std::vector<VertexNormalMap> scans(2);
  std::vector<Eigen::Isometry3d> poses(2, Eigen::Isometry3d::Identity());
  poses[1].translation() = Eigen::Vector3d(0.6, 0.05, 0.0);
  for (int f = 0; f < 2; ++f) {
    ASSERT_TRUE(cpu.Render(SurfelRenderInput::All(street), poses[f], &scans[f]).ok());
  }
  SurfelMap with_cpu, with_egl;
  ASSERT_TRUE(with_egl.SetRenderer(egl.get()).ok());
  for (int f = 0; f < 2; ++f) {
    auto a = with_cpu.Integrate(scans[f], poses[f], Timestamp::FromNanoseconds(f));
    auto b = with_egl.Integrate(scans[f], poses[f], Timestamp::FromNanoseconds(f));
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_NEAR(a->num_explained, b->num_explained, 2 + a->num_explained / 1000);
    EXPECT_NEAR(a->num_created, b->num_created, 2 + a->num_created / 1000);
    EXPECT_NEAR(a->num_confirmed, b->num_confirmed, 2 + a->num_confirmed / 1000);
  }
  EXPECT_GT(with_cpu.size(), 10000u);
  EXPECT_NEAR(static_cast<double>(with_cpu.size()), static_cast<double>(with_egl.size()),
              2.0 + with_cpu.size() / 1000.0);
  // A renderer with another image geometry is refused.
  SurfelRendererOptions other;
  other.projection.cols = 1024;
  REQUIRE_EGL(egl_other, other);
  EXPECT_EQ(with_egl.SetRenderer(egl_other.get()).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace slam_mms
