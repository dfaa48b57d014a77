#include "pipeline/surfel_renderer_factory.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "surfel/cpu_surfel_renderer.hpp"
#if SLAM_MMS_HAVE_EGL
#include "render_egl/egl_surfel_renderer.hpp"
#endif

namespace slam_mms {
namespace {

TEST(SurfelRendererFactoryTest, ChoosesCpuOnSoftwareGlAndHonoursExplicitChoice) {
  const SurfelRendererOptions options;
  auto cpu = MakeSurfelRenderer(options, SurfelRendererBackend::kCpu);
  ASSERT_TRUE(cpu.ok());
  EXPECT_EQ((*cpu)->Name(), "cpu");
  auto autos = MakeSurfelRenderer(options);
  ASSERT_TRUE(autos.ok());
#if SLAM_MMS_HAVE_EGL
  auto egl = EglSurfelRenderer::Create(options);
  const bool egl_ok = egl.ok();
  if (!egl.ok() || (*egl)->IsSoftware()) {
    EXPECT_EQ((*autos)->Name(), "cpu");
  } else {
    EXPECT_NE((*autos)->Name().find("egl"), std::string::npos);
  }
#else
  const bool egl_ok = false;  // a build without EGL: always the CPU renderer
  EXPECT_EQ((*autos)->Name(), "cpu");
#endif
  // A later kAuto choice is the first one's (on a machine without a GPU it skips the EGL probe),
  // and kEgl still tries EGL.
  auto again = MakeSurfelRenderer(options);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ((*again)->Name(), (*autos)->Name());
  auto forced = MakeSurfelRenderer(options, SurfelRendererBackend::kEgl);
  EXPECT_EQ(forced.ok(), egl_ok);
  if (!egl_ok) {
    EXPECT_EQ(forced.status().code(), StatusCode::kUnavailable);
  }
  SurfelRendererOptions bad;
  bad.min_facing_cos = 2.0;
  EXPECT_EQ(MakeSurfelRenderer(bad).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(MakeSurfelRenderer(options, SurfelRendererBackend::kCpu, 0).status().code(),
            StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace slam_mms
