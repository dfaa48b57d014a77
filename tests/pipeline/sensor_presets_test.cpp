// Sensor presets (sensor_presets.hpp): names, the default preset, and that every data-sheet beam of
// a preset lands in its own row of the preset's image, in order.

#include "slam_mms/pipeline/sensor_presets.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "slam_mms/surfel/range_projection.hpp"

namespace slam_mms {
namespace {

TEST(SensorPresetsTest, NamesRoundTripAndUnknownNamesAreListed) {
  for (LidarPreset p : AllLidarPresets()) {
    auto back = ParseLidarPreset(LidarPresetName(p));
    ASSERT_TRUE(back.ok()) << back.status().ToString();
    EXPECT_EQ(*back, p);
  }
  auto bad = ParseLidarPreset("vlp32");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("preset = 'vlp32'; must be one of hdl64e, hdl32e, vlp16"),
            std::string::npos)
      << bad.status().message();
}

TEST(SensorPresetsTest, Hdl64eIsTheDefaultAndUndoesAnotherPreset) {
  const MappingSystem::Options defaults;
  MappingSystem::Options o;
  ApplyLidarPreset(LidarPreset::kVlp16, &o);
  EXPECT_EQ(o.localizer.surfels.renderer.projection.rows, 16);
  ApplyLidarPreset(LidarPreset::kHdl64e, &o);
  const RangeProjectionOptions& a = o.localizer.surfels.renderer.projection;
  const RangeProjectionOptions& b = defaults.localizer.surfels.renderer.projection;
  EXPECT_EQ(a.rows, b.rows);
  EXPECT_EQ(a.cols, b.cols);
  EXPECT_EQ(a.fov_up_deg, b.fov_up_deg);
  EXPECT_EQ(a.fov_down_deg, b.fov_down_deg);
}

struct BeamLayout {
  LidarPreset preset;
  int beams;
  double top_deg;
  double bottom_deg;
};

// The data sheets' beams (evenly spaced for these three sensors).
TEST(SensorPresetsTest, EveryBeamHasItsOwnRowInOrder) {
  for (const BeamLayout& s : {BeamLayout{LidarPreset::kHdl32e, 32, 10.67, -30.67},
                              BeamLayout{LidarPreset::kVlp16, 16, 15.0, -15.0},
                              BeamLayout{LidarPreset::kOs1_64, 64, 16.6, -16.6}}) {
    SCOPED_TRACE(LidarPresetName(s.preset));
    MappingSystem::Options o;
    ApplyLidarPreset(s.preset, &o);
    ASSERT_TRUE(o.Validate().ok()) << o.Validate().ToString();
    auto proj = RangeProjection::Create(o.localizer.surfels.renderer.projection);
    ASSERT_TRUE(proj.ok()) << proj.status().ToString();
    ASSERT_EQ(proj->rows(), s.beams);
    for (int k = 0; k < s.beams; ++k) {
      const double el = (s.top_deg + (s.bottom_deg - s.top_deg) * k / (s.beams - 1)) * M_PI / 180;
      const Eigen::Vector3f p(static_cast<float>(10.0 * std::cos(el)), 0.0f,
                              static_cast<float>(10.0 * std::sin(el)));
      ProjectedPoint pp;
      ASSERT_TRUE(proj->Project(p, &pp)) << "beam " << k;
      EXPECT_EQ(pp.row, k) << "beam " << k << " at " << el * 180 / M_PI << " deg";
      // Near its row's centre: a quarter of a row from it at most.
      EXPECT_NEAR(pp.v, k + 0.5f, 0.25f) << "beam " << k;
    }
  }
}

TEST(SensorPresetsTest, EveryPresetBuildsAMappingSystem) {
  for (LidarPreset p : AllLidarPresets()) {
    MappingSystem::Options o;
    ApplyLidarPreset(p, &o);
    auto sys = MappingSystem::Create(o);
    EXPECT_TRUE(sys.ok()) << LidarPresetName(p) << ": " << sys.status().ToString();
  }
}

}  // namespace
}  // namespace slam_mms
