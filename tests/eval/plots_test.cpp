#include "slam_mms/eval/plots.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "eval/plot_canvas.hpp"
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
  ErrorSeries bad;
  bad.name = "x";
  bad.time_s = {0.0, 1.0};
  bad.error_m = {0.5};
  EXPECT_FALSE(PlotPositionErrors({bad}, {}, dir / "c.png").ok());
  PlotOptions tiny;
  tiny.width_px = 10;
  EXPECT_NE(PlotMapHeight(PointCloud(), {}, dir / "d.png", tiny).message().find("width_px"),
            std::string::npos);
  // Unwritable path.
  const NamedTrajectory gt{"gt", Drive(0.0, 0.0)};
  EXPECT_FALSE(PlotTrajectoriesTopView(gt, {}, {}, kT0, dir / "missing" / "t.png").ok());
  // Components of another length than the times.
  ErrorSeries bad_h;
  bad_h.name = "h";
  bad_h.time_s = {0.0, 1.0};
  bad_h.error_m = {0.5, 0.5};
  bad_h.horizontal_m = {0.1};
  bad_h.vertical_m = {0.1, 0.2};
  const Status s = PlotPositionErrors({bad_h}, {}, dir / "e.png");
  EXPECT_NE(s.message().find("horizontal"), std::string::npos) << s.ToString();
  EXPECT_FALSE(PlotGnssStatus({}, {}, dir / "f.png").ok());
  EXPECT_FALSE(PlotGnssStatus({GnssStatusTrack{}}, {}, dir / "g.png").ok());
  std::filesystem::remove_all(dir);
}

// ---- Pixel checks on the written PNGs.

cv::Mat Load(const std::filesystem::path& file) {
  cv::Mat m = cv::imread(file.string(), cv::IMREAD_COLOR);
  EXPECT_FALSE(m.empty()) << file;
  return m;
}

// Pixels within `tol` (per channel) of `color` (BGR).
int CountColor(const cv::Mat& image, const cv::Scalar& color, int tol = 6) {
  int n = 0;
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) {
      const cv::Vec3b v = image.at<cv::Vec3b>(r, c);
      if (std::abs(v[0] - color[0]) <= tol && std::abs(v[1] - color[1]) <= tol &&
          std::abs(v[2] - color[2]) <= tol) {
        ++n;
      }
    }
  }
  return n;
}

// Pixels close to the hot end of the turbo colour map (u in 0.8..1: red).
int CountHot(const cv::Mat& image) {
  int n = 0;
  for (int k = 0; k <= 20; ++k) n += CountColor(image, internal::TurboColor(0.8 + 0.01 * k), 4);
  return n;
}

// The demo drive's shape: a straight 237 m line east at 10 m/s, 10 Hz.
Trajectory Straight(double lateral_bump_m, double offset_m, double drift_per_s) {
  Trajectory t;
  for (int i = 0; i <= 237; ++i) {
    const double s = 0.1 * i;
    const double bump = lateral_bump_m * std::exp(-0.5 * std::pow((s - 15.0) / 1.0, 2));
    const Eigen::Vector3d p(10.0 * s, offset_m + bump + drift_per_s * s, 0.3 * offset_m);
    EXPECT_TRUE(t.Add(kT0.PlusSeconds(s), MakeIsometry(Eigen::Matrix3d::Identity(), p)).ok());
  }
  return t;
}

TEST(PlotsTest, StraightDriveTrajectoriesAreColouredByErrorWithAZoom) {
  const std::filesystem::path dir = OutDir();
  const NamedTrajectory gt{"ground truth", Straight(0.0, 0.0, 0.0)};
  const std::vector<NamedTrajectory> methods = {{"full", Straight(0.4, 0.0, 0.0)},
                                                {"gnss_ins", Straight(0.0, 0.15, 0.0)},
                                                {"lidar_only", Straight(0.0, 0.0, 0.05)}};
  ASSERT_TRUE(
      PlotTrajectoriesTopView(gt, methods, {}, kT0, dir / "straight_trajectories.png").ok());
  // The same methods without errors: only the colour bars are hot.
  const std::vector<NamedTrajectory> exact = {
      {"full", gt.trajectory}, {"gnss_ins", gt.trajectory}, {"lidar_only", gt.trajectory}};
  ASSERT_TRUE(PlotTrajectoriesTopView(gt, exact, {}, kT0, dir / "exact.png").ok());
  const cv::Mat img = Load(dir / "straight_trajectories.png");
  const cv::Mat flat = Load(dir / "exact.png");
  ASSERT_EQ(img.size(), flat.size());
  EXPECT_EQ(img.cols, 1400);
  // Coloured by error: the bump of full and the end of lidar_only's drift are hot.
  EXPECT_GT(CountHot(img), CountHot(flat) + 100) << CountHot(img) << " vs " << CountHot(flat);
  // The zoom panel draws every method in its palette colour (the method panels use the colour
  // map): full's blue and gnss_ins's vermillion are there, lines of a few px over some 100 px.
  EXPECT_GT(CountColor(img, internal::PaletteColor(0)), 150);
  EXPECT_GT(CountColor(img, internal::PaletteColor(1)), 150);
  // No outage: no orange band.
  const cv::Scalar band = 0.35 * internal::kOutageColor + 0.65 * cv::Scalar(255, 255, 255);
  EXPECT_EQ(CountColor(img, band, 3), 0);

  // With an outage covering some poses the band appears; one after the drive draws nothing.
  ASSERT_TRUE(PlotTrajectoriesTopView(gt, methods, {{5.0, 6.0}}, kT0, dir / "outage.png").ok());
  EXPECT_GT(CountColor(Load(dir / "outage.png"), band, 3), 200);
  ASSERT_TRUE(PlotTrajectoriesTopView(gt, methods, {{100.0, 6.0}}, kT0, dir / "late.png").ok());
  EXPECT_EQ(CountColor(Load(dir / "late.png"), band, 3), 0);

  // Without ground truth: one panel in palette colours, no colour map.
  ASSERT_TRUE(
      PlotTrajectoriesTopView({"gt", Trajectory()}, methods, {}, kT0, dir / "nogt.png").ok());
  const cv::Mat nogt = Load(dir / "nogt.png");
  EXPECT_EQ(CountHot(nogt), 0);
  EXPECT_GT(CountColor(nogt, internal::PaletteColor(0)), 50);
  Cleanup(dir);
}

TEST(PlotsTest, PositionErrorsSplitHorizontalVerticalAndShadeOnlyPresentOutages) {
  const std::filesystem::path dir = OutDir();
  const Trajectory gt = Straight(0.0, 0.0, 0.0);
  std::vector<ErrorSeries> series;
  for (const auto& [name, t] :
       std::vector<std::pair<std::string, Trajectory>>{{"full", Straight(0.4, 0.0, 0.0)},
                                                       {"gnss_ins", Straight(0.0, 0.15, 0.0)},
                                                       {"lidar_only", Straight(0.0, 0.0, 0.5)}}) {
    const StatusOr<AteResult> ate = ComputeAte(t, gt);
    ASSERT_TRUE(ate.ok());
    series.push_back(MakeErrorSeries(name, ate->errors, kT0));
  }
  // Components: gnss_ins is 0.15 m north and 0.045 m up of the ground truth everywhere.
  ASSERT_EQ(series[1].horizontal_m.size(), series[1].time_s.size());
  ASSERT_EQ(series[1].vertical_m.size(), series[1].time_s.size());
  for (size_t i = 0; i < series[1].time_s.size(); ++i) {
    EXPECT_NEAR(series[1].horizontal_m[i], 0.15, 1e-9);
    EXPECT_NEAR(series[1].vertical_m[i], 0.045, 1e-9);
    EXPECT_NEAR(std::hypot(series[1].horizontal_m[i], series[1].vertical_m[i]),
                series[1].error_m[i], 1e-9);
  }
  const cv::Scalar shade = 0.22 * internal::kOutageColor + 0.78 * cv::Scalar(255, 255, 255);
  ASSERT_TRUE(PlotPositionErrors(series, {}, dir / "pe_none.png").ok());
  EXPECT_EQ(CountColor(Load(dir / "pe_none.png"), shade, 3), 0);
  ASSERT_TRUE(PlotPositionErrors(series, {{30.0, 5.0}}, dir / "pe_late.png").ok());
  EXPECT_EQ(CountColor(Load(dir / "pe_late.png"), shade, 3), 0);
  ASSERT_TRUE(PlotPositionErrors(series, {{5.0, 6.0}}, dir / "pe_outage.png").ok());
  const cv::Mat img = Load(dir / "pe_outage.png");
  EXPECT_GT(CountColor(img, shade, 3), 1000);
  EXPECT_EQ(img.cols, 1400);
  EXPECT_EQ(img.rows, 1050);
  // Each method keeps its own scale: full's 0.4 m bump fills its panel as much as lidar_only's
  // 12 m drift fills its own; so full's blue curve spans about as many rows as lidar_only's green.
  auto rows_spanned = [&](const cv::Scalar& color) {
    int lo = img.rows, hi = -1;
    for (int r = 0; r < img.rows; ++r) {
      for (int c = 0; c < img.cols / 2; ++c) {  // the horizontal column
        const cv::Vec3b v = img.at<cv::Vec3b>(r, c);
        if (std::abs(v[0] - color[0]) <= 6 && std::abs(v[1] - color[1]) <= 6 &&
            std::abs(v[2] - color[2]) <= 6) {
          lo = std::min(lo, r);
          hi = std::max(hi, r);
        }
      }
    }
    return hi - lo;
  };
  const int full_rows = rows_spanned(internal::PaletteColor(0));
  const int lidar_rows = rows_spanned(internal::PaletteColor(2));
  EXPECT_GT(full_rows, 0.6 * lidar_rows) << full_rows << " vs " << lidar_rows;
  // The title says "(GNSS outages shaded)" only when shaded: a caller's own is dropped without
  // outages (same pixels as without it), and the title band differs when there is shading.
  PlotOptions with_note, without_note;
  with_note.title = "Position error (GNSS outages shaded)";
  without_note.title = "Position error";
  ASSERT_TRUE(PlotPositionErrors(series, {}, dir / "pe_note.png", with_note).ok());
  ASSERT_TRUE(PlotPositionErrors(series, {}, dir / "pe_plain.png", without_note).ok());
  ASSERT_TRUE(PlotPositionErrors(series, {{5.0, 6.0}}, dir / "pe_shaded.png", without_note).ok());
  const cv::Rect title_band(0, 0, 1400, 40);
  const cv::Mat plain = Load(dir / "pe_plain.png");
  EXPECT_EQ(cv::norm(Load(dir / "pe_note.png")(title_band), plain(title_band), cv::NORM_L1), 0.0);
  EXPECT_GT(cv::norm(Load(dir / "pe_shaded.png")(title_band), plain(title_band), cv::NORM_L1),
            1000.0);
  // Series without components: one column.
  for (ErrorSeries& s : series) {
    s.horizontal_m.clear();
    s.vertical_m.clear();
  }
  ASSERT_TRUE(PlotPositionErrors(series, {}, dir / "pe_3d.png").ok());
  Cleanup(dir);
}

TEST(PlotsTest, MapHeightColourRangeStatesItsClipping) {
  PointCloud map;
  for (int i = 0; i < 1000; ++i) map.Add({0.1f * i, 0.05f * (i % 40), 0.003f * i});  // 0..3 m
  StatusOr<HeightColorRange> r = MapHeightColorRange(map);
  ASSERT_TRUE(r.ok());
  EXPECT_NEAR(r->data_lo_m, 0.0, 1e-6);
  EXPECT_NEAR(r->data_hi_m, 2.997, 1e-4);
  // 1 % of 1000 points: 10 clipped at each end.
  EXPECT_NEAR(r->color_lo_m, 0.03, 1e-4);
  EXPECT_NEAR(r->color_hi_m, 2.967, 1e-4);
  EXPECT_TRUE(r->clipped());
  EXPECT_NE(r->Describe().find("clipped to the 1st..99th height percentile: 0.03..2.97 m"),
            std::string::npos)
      << r->Describe();
  EXPECT_NE(r->Describe().find("data 0.00..3.00 m"), std::string::npos) << r->Describe();
  // A flat map: nothing clipped.
  PointCloud flat;
  for (int i = 0; i < 50; ++i) flat.Add({0.1f * i, 0.0f, 1.0f});
  r = MapHeightColorRange(flat);
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->clipped());
  EXPECT_NE(r->Describe().find("colours span the data: 1.00..1.00 m"), std::string::npos);
  EXPECT_FALSE(MapHeightColorRange(PointCloud()).ok());
}

TEST(PlotsTest, GnssStatusTrackAndStrip) {
  const std::filesystem::path dir = OutDir();
  const std::vector<GnssAvailabilityInterval> availability = {
      {kT0, kT0.PlusSeconds(10.0), GnssAvailability::kValid},
      {kT0.PlusSeconds(10.0), kT0.PlusSeconds(12.0), GnssAvailability::kDegraded},
      {kT0.PlusSeconds(12.0), kT0.PlusSeconds(20.0), GnssAvailability::kOutage},
      {kT0.PlusSeconds(20.0), kT0.PlusSeconds(30.0), GnssAvailability::kValid}};
  std::vector<ScanSubmap> scans;
  for (int i = 0; i < 300; ++i) scans.push_back({kT0.PlusSeconds(0.1 * i), i / 50});  // 5 s each
  const GnssStatusTrack track = MakeGnssStatusTrack("full", availability, scans, kT0);
  ASSERT_EQ(track.spans.size(), 4u);
  EXPECT_NEAR(track.spans[2].start_s, 12.0, 1e-9);
  ASSERT_EQ(track.submaps.size(), 6u);
  EXPECT_EQ(track.submaps[2].id, 2);
  EXPECT_NEAR(track.submaps[2].start_s, 10.0, 1e-9);
  EXPECT_NEAR(track.submaps[2].end_s, 15.0, 1e-9);
  EXPECT_NEAR(track.submaps[5].end_s, 29.9, 1e-9);
  // Submap 1 (5..10 s) valid, 2 (10..15 s) outage (its worst), 4 (20..25 s) valid.
  EXPECT_EQ(WorstGnssStatus(track, 5.0, 10.0), GnssAvailability::kValid);
  EXPECT_EQ(WorstGnssStatus(track, 10.0, 11.0), GnssAvailability::kDegraded);
  EXPECT_EQ(WorstGnssStatus(track, 10.0, 15.0), GnssAvailability::kOutage);
  EXPECT_EQ(WorstGnssStatus(track, 20.0, 25.0), GnssAvailability::kValid);
  EXPECT_EQ(WorstGnssStatus(track, 15.0, 15.0), GnssAvailability::kOutage);  // a point in time

  const GnssStatusTrack lidar = MakeGnssStatusTrack("lidar_only", {}, scans, kT0);
  PlotOptions o;
  o.height_px = 600;
  ASSERT_TRUE(PlotGnssStatus({track, lidar}, {{12.0, 8.0}}, dir / "gnss_status.png", o).ok());
  const cv::Mat img = Load(dir / "gnss_status.png");
  // The outage (vermillion) and available (bluish green) strips are drawn.
  EXPECT_GT(CountColor(img, cv::Scalar(0, 94, 213), 2), 3000);
  EXPECT_GT(CountColor(img, cv::Scalar(115, 158, 0), 2), 1000);
  // All available: no outage colour but the legend's swatch (36 x ~16 px).
  const GnssStatusTrack ok = MakeGnssStatusTrack(
      "gnss_ins", {{kT0, kT0.PlusSeconds(30.0), GnssAvailability::kValid}}, scans, kT0);
  ASSERT_TRUE(PlotGnssStatus({ok}, {}, dir / "gnss_ok.png", o).ok());
  EXPECT_LT(CountColor(Load(dir / "gnss_ok.png"), cv::Scalar(0, 94, 213), 2), 700);
  Cleanup(dir);
}

// ---- Titles fit their panels.

TEST(PlotsTest, FitTextKeepsEveryLineInsideTheWidth) {
  const std::vector<std::string> titles = {
      "full: RMS 0.049 m, max 0.090 m",
      "gnss_ins_smoothed: RMS 0.24 m, max 0.44 m",
      "a_very_long_method_name_from_a_host_application: RMS 123.4 m, max 1234.5 m",
      "Zoom: largest error of gnss_ins_smoothed, 0.44 m at t = 123.4 s",
      "no_space_in_this_title_at_all_so_it_cannot_be_broken_anywhere_into_two_lines",
      "x"};
  for (const std::string& title : titles) {
    for (int width : {120, 200, 300, 358, 466, 700, 1400}) {
      for (int max_lines : {1, 2}) {
        const internal::TextLayout t = internal::FitText(title, width, 0.8, 0.5, 2, max_lines);
        SCOPED_TRACE(title + " in " + std::to_string(width) + " px");
        ASSERT_FALSE(t.lines.empty());
        EXPECT_LE(static_cast<int>(t.lines.size()), max_lines);
        EXPECT_GE(t.scale, 0.5 - 1e-9);
        EXPECT_LE(t.scale, 0.8 + 1e-9);
        EXPECT_LE(t.width_px, width);
        for (const std::string& line : t.lines) {
          int base = 0;
          EXPECT_LE(
              cv::getTextSize(line, cv::FONT_HERSHEY_SIMPLEX, t.scale, t.thickness, &base).width,
              width)
              << line;
          EXPECT_FALSE(line.empty());
        }
      }
    }
  }
  // A title that fits keeps its size and line.
  const internal::TextLayout fits =
      internal::FitText("full: RMS 0.049 m, max 0.090 m", 1400, 0.8, 0.5, 2, 2);
  ASSERT_EQ(fits.lines.size(), 1u);
  EXPECT_EQ(fits.lines[0], "full: RMS 0.049 m, max 0.090 m");
  EXPECT_DOUBLE_EQ(fits.scale, 0.8);
  EXPECT_EQ(fits.thickness, 2);
  // Too wide for one readable line: the method name over its numbers, both whole.
  const internal::TextLayout two =
      internal::FitText("gnss_ins_smoothed: RMS 0.24 m, max 0.44 m", 300, 0.8, 0.5, 2, 2);
  ASSERT_EQ(two.lines.size(), 2u);
  EXPECT_EQ(two.lines[0], "gnss_ins_smoothed");
  EXPECT_EQ(two.lines[1], "RMS 0.24 m, max 0.44 m");
  EXPECT_GT(two.line_step_px, 10);
  // Too wide even at the smallest scale: cut, ending in "...".
  const internal::TextLayout cut = internal::FitText(titles[4], 200, 0.8, 0.5, 2, 2);
  ASSERT_EQ(cut.lines.size(), 1u);
  EXPECT_DOUBLE_EQ(cut.scale, 0.5);
  EXPECT_EQ(cut.lines[0].substr(cut.lines[0].size() - 3), "...");
  EXPECT_EQ(cut.lines[0].substr(0, 10), titles[4].substr(0, 10));
}

// The axes boxes of a figure of small multiples as (left edge, top): columns with a vertical run
// of >= 60 px of the frame's grey with y ticks (6 px of the same grey, between the frame's top and
// bottom lines) left of it.
std::vector<cv::Point> AxesLeftTops(const cv::Mat& img) {
  const cv::Vec3b grey(60, 60, 60);
  auto is_grey = [&](int r, int c) { return img.at<cv::Vec3b>(r, c) == grey; };
  std::vector<cv::Point> out;
  for (int c = 6; c < img.cols; ++c) {
    int run = 0;
    for (int r = 0; r <= img.rows; ++r) {
      if (r < img.rows && is_grey(r, c)) {
        ++run;
        continue;
      }
      if (run >= 60) {
        int ticks = 0;
        for (int y = r - run + 1; y < r - 1; ++y) {
          bool tick = true;
          for (int k = 1; k <= 6; ++k) tick = tick && is_grey(y, c - k);
          ticks += tick ? 1 : 0;
        }
        if (ticks >= 2) out.emplace_back(c, r - run);
      }
      run = 0;
    }
  }
  return out;
}

int NonWhite(const cv::Mat& img, const cv::Rect& rect) {
  int n = 0;
  const cv::Rect r = rect & cv::Rect(0, 0, img.cols, img.rows);
  for (int y = r.y; y < r.br().y; ++y) {
    for (int x = r.x; x < r.br().x; ++x) n += img.at<cv::Vec3b>(y, x) != cv::Vec3b(255, 255, 255);
  }
  return n;
}

// Once around a 100 m x `north_m` block at 10 m/s, 10 Hz (the demo drive's: 70 m), drifting north.
Trajectory Block(double north_m, double drift_per_s) {
  Trajectory t;
  const int n = static_cast<int>(200.0 + 2.0 * north_m);
  for (int i = 0; i <= n; ++i) {
    const double d = i;  // metres along the loop
    Eigen::Vector3d p = d < 100.0             ? Eigen::Vector3d(d, 0.0, 0.0)
                        : d < 100.0 + north_m ? Eigen::Vector3d(100.0, d - 100.0, 0.0)
                        : d < 200.0 + north_m ? Eigen::Vector3d(200.0 + north_m - d, north_m, 0.0)
                                              : Eigen::Vector3d(0.0, n - d, 0.0);
    p.y() += drift_per_s * 0.1 * i;
    EXPECT_TRUE(t.Add(kT0.PlusSeconds(0.1 * i), MakeIsometry(Eigen::Matrix3d::Identity(), p)).ok());
  }
  return t;
}

TEST(PlotsTest, PanelTitlesStayInsideTheirPanels) {
  const std::filesystem::path dir = OutDir();
  const NamedTrajectory gt{"ground truth", Drive(0.0, 0.0)};
  // The app's four methods, and a host's long names (too long for one line in a panel).
  const std::vector<std::vector<std::string>> name_sets = {
      {"full", "gnss_ins", "gnss_ins_smoothed", "lidar_only"},
      {"full_with_loop_closures_v2", "gnss_ins_smoothed_relaxed",
       "a_very_long_method_name_without_any_break", "lidar_only"}};
  int case_index = 0;
  for (const std::vector<std::string>& names : name_sets) {
    // Panels in two columns (a figure of eight, the demo's block) and in three (a square block).
    for (double north_m : {0.0, 70.0, 100.0}) {
      const bool block = north_m > 0.0;
      const NamedTrajectory block_gt{"ground truth", Block(north_m, 0.0)};
      std::vector<NamedTrajectory> methods;
      for (size_t i = 0; i < names.size(); ++i) {
        methods.push_back({names[i], block ? Block(north_m, 0.01 + 0.03 * i)
                                           : Drive(0.01 + 0.04 * i, 0.2 + 0.2 * i)});
      }
      const std::filesystem::path png = dir / ("titles_" + std::to_string(case_index++) + ".png");
      ASSERT_TRUE(
          PlotTrajectoriesTopView(block ? block_gt : gt, methods, {{12.0, 8.0}}, kT0, png).ok());
      const cv::Mat img = Load(png);
      const std::vector<cv::Point> boxes = AxesLeftTops(img);
      SCOPED_TRACE(png.filename().string());
      ASSERT_EQ(boxes.size(), names.size() + 1);  // the method panels and the zoom
      for (size_t i = 0; i < boxes.size(); ++i) {
        const int left = boxes[i].x - internal::PlotCanvas::kLeftPx;
        const int top = boxes[i].y - internal::PlotCanvas::kTopPx;
        ASSERT_GE(left, 0);
        ASSERT_GE(top, 0);
        // The panel's right edge: the next panel's left in the same row, else the figure's.
        int right = img.cols;
        for (const cv::Point& b : boxes) {
          const int l = b.x - internal::PlotCanvas::kLeftPx;
          if (b.y == boxes[i].y && l > left) right = std::min(right, l);
        }
        // The title band down to the (last) baseline, above the colour bar's label.
        const cv::Rect band(left, top, right - left, internal::PlotCanvas::kTopPx - 21);
        // A title is drawn, and no title pixel lies within 10 px of the panel's sides (so two
        // neighbours' titles are 20 px apart or more).
        EXPECT_GT(NonWhite(img, band), 150) << "panel " << i;
        EXPECT_EQ(NonWhite(img, {left, top, 10, band.height}), 0) << "panel " << i << " left";
        EXPECT_EQ(NonWhite(img, {right - 10, top, 10, band.height}), 0)
            << "panel " << i << " right";
      }
    }
  }
  Cleanup(dir);
}

}  // namespace
}  // namespace slam_mms::eval
