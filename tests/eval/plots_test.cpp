#include "slam_mms/eval/plots.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>

#include "slam_mms/core/lie.hpp"
#include "testing/test_data.hpp"

namespace slam_mms::eval {
namespace {

const Timestamp kT0 = Timestamp::FromNanoseconds(1317042651000000000LL);

// Width and height from a PNG's IHDR chunk; {0, 0} when the file is not a PNG.
std::pair<int, int> PngSize(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  unsigned char h[24] = {};
  in.read(reinterpret_cast<char*>(h), sizeof(h));
  const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (!in || std::memcmp(h, sig, 8) != 0 || std::memcmp(h + 12, "IHDR", 4) != 0) return {0, 0};
  auto be32 = [&](int o) { return (h[o] << 24) | (h[o + 1] << 16) | (h[o + 2] << 8) | h[o + 3]; };
  return {be32(16), be32(20)};
}

// A drive around a block with a figure of eight; methods with growing drift.
Trajectory Drive(double drift_per_s, double wobble) {
  Trajectory t;
  for (int i = 0; i <= 600; ++i) {
    const double s = 0.1 * i;
    const double a = 2.0 * M_PI * s / 60.0;
    Eigen::Vector3d p(120.0 * std::sin(a), 60.0 * std::sin(2.0 * a), 2.0 * std::sin(a));
    p += Eigen::Vector3d(drift_per_s * s, -0.5 * drift_per_s * s, 0.0);
    p.y() += wobble * std::sin(3.0 * s);
    EXPECT_TRUE(t.Add(kT0.PlusSeconds(s), MakeIsometry(Eigen::Matrix3d::Identity(), p)).ok());
  }
  return t;
}

std::filesystem::path OutDir() {
  // SLAM_MMS_PLOT_DIR keeps the PNGs for looking at them; else a temp folder removed at the end.
  if (const char* env = std::getenv("SLAM_MMS_PLOT_DIR"); env != nullptr && *env != '\0') {
    std::filesystem::create_directories(env);
    return env;
  }
  return slam_mms::testing::MakeTempDir("eval_plots");
}

void Cleanup(const std::filesystem::path& dir) {
  if (std::getenv("SLAM_MMS_PLOT_DIR") == nullptr) std::filesystem::remove_all(dir);
}

TEST(PlotsTest, TrajectoriesErrorsAndMapAreWrittenAsPng) {
  const std::filesystem::path dir = OutDir();
  const NamedTrajectory gt{"ground truth", Drive(0.0, 0.0)};
  const std::vector<NamedTrajectory> methods = {
      {"full", Drive(0.01, 0.3)}, {"gnss_ins", Drive(0.03, 0.8)}, {"lidar_only", Drive(0.25, 0.2)}};
  const std::vector<OutageWindow> outages = {{12.0, 8.0}, {40.0, 6.0}};
  ASSERT_TRUE(PlotTrajectoriesTopView(gt, methods, outages, kT0, dir / "trajectories.png").ok());
  // Equal scale: the 260 x 145 m drive fits the width, the height shrinks.
  const auto [tw, th] = PngSize(dir / "trajectories.png");
  EXPECT_EQ(tw, 1400);
  EXPECT_GT(th, 500);
  EXPECT_LT(th, 1050);

  std::vector<ErrorSeries> series;
  for (const NamedTrajectory& m : methods) {
    const StatusOr<AteResult> ate = ComputeAte(m.trajectory, gt.trajectory);
    ASSERT_TRUE(ate.ok());
    series.push_back(MakeErrorSeries(m.name, ate->errors, kT0));
  }
  EXPECT_EQ(series[0].time_s.size(), 601u);
  EXPECT_NEAR(series[0].time_s.back(), 60.0, 1e-9);
  PlotOptions wide;
  wide.width_px = 1400;
  wide.height_px = 600;
  ASSERT_TRUE(PlotPositionErrors(series, outages, dir / "position_error.png", wide).ok());
  EXPECT_EQ(PngSize(dir / "position_error.png"), std::make_pair(1400, 600));

  // A street-like map: ground, two building fronts with windows, a few poles.
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  PointCloud map;
  for (int i = 0; i < 200000; ++i) {
    const float x = -60.0f + 120.0f * u(rng), y = -15.0f + 30.0f * u(rng);
    map.Add({x, y, 0.02f * std::sin(0.2f * x)});
  }
  for (int i = 0; i < 100000; ++i) {
    const float x = -60.0f + 120.0f * u(rng), z = 12.0f * u(rng);
    map.Add({x, (i % 2 == 0) ? 14.0f : -14.0f, z});
  }
  for (int k = 0; k < 12; ++k) {
    for (int i = 0; i < 2000; ++i) {
      map.Add({-55.0f + 10.0f * k + 0.2f * u(rng), 8.0f + 0.2f * u(rng), 6.0f * u(rng)});
    }
  }
  std::vector<Eigen::Vector3d> overlay;
  for (int i = 0; i <= 100; ++i) overlay.emplace_back(-50.0 + i, 2.0 * std::sin(0.05 * i), 0.0);
  ASSERT_TRUE(PlotMapHeight(map, overlay, dir / "map_height.png").ok());
  const auto [mw, mh] = PngSize(dir / "map_height.png");
  EXPECT_EQ(mw, 1400);
  EXPECT_GT(mh, 360);
  EXPECT_LT(mh, 700);
  Cleanup(dir);
}

TEST(PlotsTest, BadInputsFail) {
  const std::filesystem::path dir = slam_mms::testing::MakeTempDir("eval_plots_bad");
  EXPECT_EQ(PlotTrajectoriesTopView({"gt", Trajectory()}, {}, {}, kT0, dir / "a.png").code(),
            StatusCode::kInvalidArgument);
  EXPECT_FALSE(PlotMapHeight(PointCloud(), {}, dir / "b.png").ok());
  ErrorSeries bad{"x", {0.0, 1.0}, {0.5}};
  EXPECT_FALSE(PlotPositionErrors({bad}, {}, dir / "c.png").ok());
  PlotOptions tiny;
  tiny.width_px = 10;
  EXPECT_NE(PlotMapHeight(PointCloud(), {}, dir / "d.png", tiny).message().find("width_px"),
            std::string::npos);
  // Unwritable path.
  const NamedTrajectory gt{"gt", Drive(0.0, 0.0)};
  EXPECT_FALSE(PlotTrajectoriesTopView(gt, {}, {}, kT0, dir / "missing" / "t.png").ok());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace slam_mms::eval
