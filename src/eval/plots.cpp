#include "slam_mms/eval/plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "eval/plot_canvas.hpp"

namespace slam_mms::eval {
namespace {

using internal::LegendEntry;
using internal::PaletteColor;
using internal::PlotCanvas;

using internal::Bounds;
using internal::kBlackColor;
using internal::kOutageColor;

std::string Metres(double v) {
  char buf[32];
  const double a = std::abs(v);
  std::snprintf(buf, sizeof(buf), a < 0.1 ? "%.3f m" : a < 10.0 ? "%.2f m" : "%.1f m", v);
  return buf;
}

}  // namespace

Status PlotOptions::Validate() const {
  if (width_px < 320 || width_px > 8000) {
    return InvalidArgumentError("PlotOptions::width_px = " + std::to_string(width_px) +
                                "; must be in [320, 8000]");
  }
  if (height_px < 240 || height_px > 8000) {
    return InvalidArgumentError("PlotOptions::height_px = " + std::to_string(height_px) +
                                "; must be in [240, 8000]");
  }
  return OkStatus();
}

ErrorSeries MakeErrorSeries(const std::string& name, const std::vector<PoseError>& errors,
                            Timestamp reference) {
  ErrorSeries s;
  s.name = name;
  s.time_s.reserve(errors.size());
  s.error_m.reserve(errors.size());
  s.horizontal_m.reserve(errors.size());
  s.vertical_m.reserve(errors.size());
  for (const PoseError& e : errors) {
    s.time_s.push_back(e.stamp.SecondsSince(reference));
    s.error_m.push_back(e.position_error_m);
    s.horizontal_m.push_back(e.position_error_world.head<2>().norm());
    s.vertical_m.push_back(e.position_error_world.z());
  }
  return s;
}

Status PlotPositionErrors(const std::vector<ErrorSeries>& series,
                          const std::vector<OutageWindow>& outages,
                          const std::filesystem::path& png_file, const PlotOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  double t_lo = std::numeric_limits<double>::infinity(), t_hi = -t_lo;
  bool components = !series.empty();
  for (const ErrorSeries& s : series) {
    if (s.time_s.size() != s.error_m.size()) {
      return InvalidArgumentError("PlotPositionErrors: series \"" + s.name + "\" has " +
                                  std::to_string(s.time_s.size()) + " times but " +
                                  std::to_string(s.error_m.size()) + " errors");
    }
    for (const auto* v : {&s.horizontal_m, &s.vertical_m}) {
      if (!v->empty() && v->size() != s.time_s.size()) {
        return InvalidArgumentError(
            "PlotPositionErrors: series \"" + s.name + "\" has " + std::to_string(s.time_s.size()) +
            " times but " + std::to_string(v->size()) +
            (v == &s.horizontal_m ? " horizontal" : " vertical") + " errors");
      }
    }
    components = components && !s.horizontal_m.empty() && !s.vertical_m.empty();
    for (size_t i = 0; i < s.time_s.size(); ++i) {
      if (!std::isfinite(s.time_s[i]) || !std::isfinite(s.error_m[i])) continue;
      t_lo = std::min(t_lo, s.time_s[i]);
      t_hi = std::max(t_hi, s.time_s[i]);
    }
  }
  if (!(t_lo <= t_hi)) return InvalidArgumentError("PlotPositionErrors: no finite sample to draw");
  if (!(t_hi > t_lo)) t_hi = t_lo + 1.0;
  bool shaded = false;
  for (const OutageWindow& w : outages) {
    shaded = shaded || (w.duration_s > 0.0 && w.start_s < t_hi && w.start_s + w.duration_s > t_lo);
  }

  // Small multiples: a row per method, its own y scale; columns horizontal | vertical.
  constexpr int kTitlePx = 46, kTopPx = 34, kBottomPx = 34, kLastBottomPx = 72, kRightPx = 24;
  const int rows = static_cast<int>(series.size());
  const int cols = components ? 2 : 1;
  const int row_h =
      std::max(110, (options.height_px - kTitlePx - (kLastBottomPx - kBottomPx)) / rows);
  const int col_w = options.width_px / cols;
  cv::Mat figure(kTitlePx + rows * row_h + (kLastBottomPx - kBottomPx), cols * col_w, CV_8UC3,
                 cv::Scalar(255, 255, 255));
  for (int r = 0; r < rows; ++r) {
    const ErrorSeries& s = series[r];
    const bool last = r + 1 == rows;
    for (int c = 0; c < cols; ++c) {
      const std::vector<double>& v =
          !components ? s.error_m : (c == 0 ? s.horizontal_m : s.vertical_m);
      const bool is_vertical = components && c == 1;
      double lo = 0.0, hi = 0.0, sum_sq = 0.0, max_abs = 0.0;
      size_t n = 0;
      std::vector<cv::Point2d> pts;
      pts.reserve(v.size());
      for (size_t k = 0; k < v.size(); ++k) {
        if (!std::isfinite(s.time_s[k]) || !std::isfinite(v[k])) {
          pts.emplace_back(std::numeric_limits<double>::quiet_NaN(), 0.0);
          continue;
        }
        pts.emplace_back(s.time_s[k], v[k]);
        lo = std::min(lo, v[k]);
        hi = std::max(hi, v[k]);
        sum_sq += v[k] * v[k];
        max_abs = std::max(max_abs, std::abs(v[k]));
        ++n;
      }
      if (!(hi - lo > 1e-6)) hi = lo + 0.01;
      const double pad = 0.08 * (hi - lo);
      const int h = row_h + (last ? kLastBottomPx - kBottomPx : 0);
      PlotCanvas canvas(col_w, h, kRightPx, kTopPx, last ? kLastBottomPx : kBottomPx);
      canvas.SetRange(t_lo, t_hi, is_vertical ? lo - pad : 0.0, hi + pad, /*equal_aspect=*/false);
      canvas.DrawGrid();
      if (shaded) {
        for (const OutageWindow& w : outages) {
          canvas.ShadeXSpan(w.start_s, w.start_s + w.duration_s, kOutageColor, 0.22);
        }
      }
      if (is_vertical) canvas.Polyline({{t_lo, 0.0}, {t_hi, 0.0}}, cv::Scalar(120, 120, 120), 1);
      canvas.Polyline(pts, internal::PaletteColor(r), 2);
      const std::string what = !components ? "3-D error"
                               : c == 0    ? "horizontal"
                                           : "vertical (up +)";
      std::string title = s.name + " " + what;
      if (n > 0) {
        title += ": RMS " + Metres(std::sqrt(sum_sq / n)) + ", max |e| " + Metres(max_abs);
      }
      canvas.DrawAxes(last ? "time since start [s]" : "", c == 0 ? "error [m]" : "", title);
      canvas.image().copyTo(figure(cv::Rect(c * col_w, kTitlePx + r * row_h, col_w, h)));
    }
  }
  std::string title = options.title.empty() ? "Position error over time" : options.title;
  // A caller's own "(GNSS outages shaded)" is dropped: it is appended here only when true.
  const std::string kShadedNote = " (GNSS outages shaded)";
  for (size_t at = title.find(kShadedNote); at != std::string::npos; at = title.find(kShadedNote)) {
    title.erase(at, kShadedNote.size());
  }
  if (shaded) title += kShadedNote;
  int base = 0;
  const cv::Size sz = cv::getTextSize(title, cv::FONT_HERSHEY_SIMPLEX, 0.8, 2, &base);
  cv::putText(figure, title, {std::max(4, figure.cols / 2 - sz.width / 2), 30},
              cv::FONT_HERSHEY_SIMPLEX, 0.8, kBlackColor, 2, cv::LINE_AA);
  return internal::SavePng(figure, png_file);
}

std::string HeightColorRange::Describe() const {
  char note[200];
  if (clipped()) {
    std::snprintf(note, sizeof(note),
                  "colours clipped to the 1st..99th height percentile: %.2f..%.2f m; data "
                  "%.2f..%.2f m",
                  color_lo_m, color_hi_m, data_lo_m, data_hi_m);
  } else {
    std::snprintf(note, sizeof(note), "colours span the data: %.2f..%.2f m", data_lo_m, data_hi_m);
  }
  return note;
}

StatusOr<HeightColorRange> MapHeightColorRange(const PointCloud& map) {
  std::vector<float> heights;
  heights.reserve(map.size());
  for (const Eigen::Vector3f& p : map.points()) {
    if (p.allFinite()) heights.push_back(p.z());
  }
  if (heights.empty()) return InvalidArgumentError("PlotMapHeight: the map has no finite point");
  HeightColorRange r;
  const auto [min_it, max_it] = std::minmax_element(heights.begin(), heights.end());
  r.data_lo_m = *min_it;
  r.data_hi_m = *max_it;
  // 1st..99th percentile, so a few outliers do not wash out the colours.
  const size_t n = heights.size();
  std::nth_element(heights.begin(), heights.begin() + n / 100, heights.end());
  r.color_lo_m = heights[n / 100];
  std::nth_element(heights.begin(), heights.begin() + (n - 1 - n / 100), heights.end());
  r.color_hi_m = heights[n - 1 - n / 100];
  if (!(r.color_hi_m > r.color_lo_m)) {
    r.color_lo_m -= 0.5;
    r.color_hi_m += 0.5;
  }
  return r;
}

Status PlotMapHeight(const PointCloud& map, const std::vector<Eigen::Vector3d>& overlay,
                     const std::filesystem::path& png_file, const PlotOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  Bounds b;
  for (const Eigen::Vector3f& p : map.points()) {
    if (p.allFinite()) b.Add(p.x(), p.y());
  }
  if (!b.valid()) return InvalidArgumentError("PlotMapHeight: the map has no finite point");
  b.Pad(0.03, 1.0);

  SLAM_MMS_ASSIGN_OR_RETURN(const HeightColorRange range, MapHeightColorRange(map));
  const double z_lo = range.color_lo_m, z_hi = range.color_hi_m;

  const int colorbar_w = 150;
  const cv::Size fig = PlotCanvas::FitEqualAspect(b.x_hi - b.x_lo, b.y_hi - b.y_lo,
                                                  options.width_px, options.height_px, colorbar_w);
  // A taller top margin: the clipping note goes under the title.
  PlotCanvas canvas(fig.width, fig.height, colorbar_w, PlotCanvas::kTopPx + 30,
                    PlotCanvas::kBottomPx);
  canvas.SetRange(b.x_lo, b.x_hi, b.y_lo, b.y_hi, /*equal_aspect=*/true);
  canvas.DrawGrid();

  // Top surface: the highest point per pixel.
  const cv::Rect area = canvas.PlotArea();
  cv::Mat top(area.size(), CV_32F, cv::Scalar(-std::numeric_limits<float>::infinity()));
  for (const Eigen::Vector3f& p : map.points()) {
    if (!p.allFinite()) continue;
    const cv::Point2d px = canvas.ToPixel(p.x(), p.y());
    const int c = static_cast<int>(std::floor(px.x)) - area.x;
    const int r = static_cast<int>(std::floor(px.y)) - area.y;
    if (c < 0 || r < 0 || c >= area.width || r >= area.height) continue;
    float& v = top.at<float>(r, c);
    v = std::max(v, p.z());
  }
  // Close the gaps between sparse points: empty pixels take the highest of their 8 neighbours,
  // twice (fills holes up to 4 px wide without growing isolated points much).
  for (int pass = 0; pass < 2; ++pass) {
    cv::Mat grown;
    cv::dilate(top, grown, cv::Mat::ones(3, 3, CV_8U));
    cv::Mat empty = top == -std::numeric_limits<float>::infinity();
    grown.copyTo(top, empty);
  }
  cv::Mat level(area.size(), CV_8U, cv::Scalar(0));
  cv::Mat occupied(area.size(), CV_8U, cv::Scalar(0));
  for (int r = 0; r < area.height; ++r) {
    for (int c = 0; c < area.width; ++c) {
      const float z = top.at<float>(r, c);
      if (!std::isfinite(z)) continue;
      const double u = std::clamp((z - z_lo) / (z_hi - z_lo), 0.0, 1.0);
      level.at<uint8_t>(r, c) = static_cast<uint8_t>(std::lround(u * 255.0));
      occupied.at<uint8_t>(r, c) = 255;
    }
  }
  cv::Mat colored;
  cv::applyColorMap(level, colored, cv::COLORMAP_TURBO);
  colored.copyTo(canvas.image()(area), occupied);

  if (!overlay.empty()) {
    std::vector<cv::Point2d> pts;
    pts.reserve(overlay.size());
    for (const Eigen::Vector3d& p : overlay) pts.emplace_back(p.x(), p.y());
    canvas.Polyline(pts, kBlackColor, 2);
  }

  // Colour bar with height ticks; a triangle at an end beyond which data were clipped.
  const int bar_x = area.br().x + 28, bar_w = 22;
  const int bar_y = area.y + 16, bar_h = area.height - 32;
  canvas.TurboColorBar(cv::Rect(bar_x, bar_y, bar_w, bar_h), z_lo, z_hi, "");
  const bool clipped_hi = range.data_hi_m > z_hi + 0.005;
  const bool clipped_lo = range.data_lo_m < z_lo - 0.005;
  if (clipped_hi) {
    const std::vector<cv::Point> tri = {
        {bar_x, bar_y - 2}, {bar_x + bar_w, bar_y - 2}, {bar_x + bar_w / 2, bar_y - 14}};
    cv::fillConvexPoly(canvas.image(), tri, internal::TurboColor(1.0), cv::LINE_AA);
  }
  if (clipped_lo) {
    const int y = bar_y + bar_h + 1;
    const std::vector<cv::Point> tri = {
        {bar_x, y + 1}, {bar_x + bar_w, y + 1}, {bar_x + bar_w / 2, y + 13}};
    cv::fillConvexPoly(canvas.image(), tri, internal::TurboColor(0.0), cv::LINE_AA);
  }
  canvas.Text("z [m]", {bar_x - 4, bar_y - 20}, 0.55, kBlackColor);
  // The clipping, stated under the title.
  const std::string note = range.Describe();
  int base = 0;
  const cv::Size nsz = cv::getTextSize(note, cv::FONT_HERSHEY_SIMPLEX, 0.48, 1, &base);
  canvas.Text(note, {std::max(2, area.x + area.width / 2 - nsz.width / 2), area.y - 8}, 0.48,
              cv::Scalar(60, 60, 60));

  canvas.DrawAxes("x east [m]", "y north [m]", "");
  // The title above the note (DrawAxes would put it where the note is).
  const std::string title =
      options.title.empty() ? "Map from above, coloured by height" : options.title;
  const cv::Size tsz = cv::getTextSize(title, cv::FONT_HERSHEY_SIMPLEX, 0.8, 2, &base);
  canvas.Text(title, {std::max(2, area.x + area.width / 2 - tsz.width / 2), area.y - 34}, 0.8,
              kBlackColor, 2);
  return internal::SavePng(canvas.image(), png_file);
}

}  // namespace slam_mms::eval
