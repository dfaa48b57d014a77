#include "slam_mms/eval/plots.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "eval/plot_canvas.hpp"

namespace slam_mms::eval {
namespace {

using internal::LegendEntry;
using internal::PaletteColor;
using internal::PlotCanvas;

const cv::Scalar kOutageColor(0, 140, 255);  // orange (BGR)
const cv::Scalar kBlack(0, 0, 0);

struct Bounds {
  double x_lo = std::numeric_limits<double>::infinity();
  double x_hi = -std::numeric_limits<double>::infinity();
  double y_lo = std::numeric_limits<double>::infinity();
  double y_hi = -std::numeric_limits<double>::infinity();
  void Add(double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y)) return;
    x_lo = std::min(x_lo, x);
    x_hi = std::max(x_hi, x);
    y_lo = std::min(y_lo, y);
    y_hi = std::max(y_hi, y);
  }
  bool valid() const { return x_lo <= x_hi && y_lo <= y_hi; }
  void Pad(double fraction, double min_pad) {
    const double px = std::max(min_pad, fraction * (x_hi - x_lo));
    const double py = std::max(min_pad, fraction * (y_hi - y_lo));
    x_lo -= px;
    x_hi += px;
    y_lo -= py;
    y_hi += py;
  }
};

Status SaveCanvas(const PlotCanvas& canvas, const std::filesystem::path& file) {
  if (!canvas.Save(file.string())) {
    return NotFoundError("cannot write PNG " + file.string() +
                         " (missing folder, no permission, or no PNG support in OpenCV)");
  }
  return OkStatus();
}

std::vector<cv::Point2d> XY(const Trajectory& t) {
  std::vector<cv::Point2d> pts;
  pts.reserve(t.size());
  for (const StampedPose& p : t.poses()) {
    pts.emplace_back(p.T_world_body.translation().x(), p.T_world_body.translation().y());
  }
  return pts;
}

// The parts of `t` inside any window, as polylines (NaN breaks between runs).
std::vector<cv::Point2d> InsideOutages(const Trajectory& t,
                                       const std::vector<OutageWindow>& outages,
                                       Timestamp reference) {
  std::vector<cv::Point2d> pts;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  bool prev_inside = false;
  for (const StampedPose& p : t.poses()) {
    bool inside = false;
    for (const OutageWindow& w : outages) inside = inside || w.Contains(p.stamp, reference);
    if (inside) {
      pts.emplace_back(p.T_world_body.translation().x(), p.T_world_body.translation().y());
    } else if (prev_inside) {
      pts.emplace_back(nan, nan);
    }
    prev_inside = inside;
  }
  return pts;
}

// Draws `pts` with the given thickness on a copy and blends it in (translucent band).
void TranslucentPolyline(PlotCanvas& canvas, const std::vector<cv::Point2d>& pts,
                         const cv::Scalar& color, int thickness, double alpha) {
  cv::Mat before = canvas.image().clone();
  canvas.Polyline(pts, color, thickness);
  cv::addWeighted(canvas.image(), alpha, before, 1.0 - alpha, 0.0, canvas.image());
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

Status PlotTrajectoriesTopView(const NamedTrajectory& ground_truth,
                               const std::vector<NamedTrajectory>& methods,
                               const std::vector<OutageWindow>& outages, Timestamp outage_reference,
                               const std::filesystem::path& png_file, const PlotOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  Bounds b;
  for (const StampedPose& p : ground_truth.trajectory.poses()) {
    b.Add(p.T_world_body.translation().x(), p.T_world_body.translation().y());
  }
  for (const NamedTrajectory& m : methods) {
    for (const StampedPose& p : m.trajectory.poses()) {
      b.Add(p.T_world_body.translation().x(), p.T_world_body.translation().y());
    }
  }
  if (!b.valid()) return InvalidArgumentError("PlotTrajectoriesTopView: no finite pose to draw");
  b.Pad(0.06, 5.0);

  // The legend sits right of the axes (a top view has no free corner in general).
  const bool has_gt = !ground_truth.trajectory.empty();
  std::vector<LegendEntry> legend;
  if (has_gt) legend.push_back({ground_truth.name, kBlack, 2, LegendEntry::Kind::kLine});
  for (size_t i = 0; i < methods.size(); ++i) {
    legend.push_back({methods[i].name, PaletteColor(i), 2, LegendEntry::Kind::kLine});
  }
  if (!outages.empty()) {
    legend.push_back({"GNSS outage", 0.35 * kOutageColor + 0.65 * cv::Scalar(255, 255, 255), 10,
                      LegendEntry::Kind::kLine});
  }
  legend.push_back({"start", kBlack, 2, LegendEntry::Kind::kDot});
  const int right_px = PlotCanvas::LegendSize(legend).width + 40;
  const cv::Size fig = PlotCanvas::FitEqualAspect(b.x_hi - b.x_lo, b.y_hi - b.y_lo,
                                                  options.width_px, options.height_px, right_px);
  PlotCanvas canvas(fig.width, fig.height, right_px);
  canvas.SetRange(b.x_lo, b.x_hi, b.y_lo, b.y_hi, /*equal_aspect=*/true);
  canvas.DrawGrid();

  if (has_gt && !outages.empty()) {
    const std::vector<cv::Point2d> band =
        InsideOutages(ground_truth.trajectory, outages, outage_reference);
    TranslucentPolyline(canvas, band, kOutageColor, 16, 0.35);
  }
  if (has_gt) {
    canvas.Polyline(XY(ground_truth.trajectory), kBlack, 2);
  }
  for (size_t i = 0; i < methods.size(); ++i) {
    const cv::Scalar color = PaletteColor(i);
    canvas.Polyline(XY(methods[i].trajectory), color, 2);
    if (!outages.empty()) {
      canvas.Polyline(InsideOutages(methods[i].trajectory, outages, outage_reference), color, 5);
    }
  }
  // Start marker on the ground truth (or the first method).
  const Trajectory* first =
      has_gt ? &ground_truth.trajectory : (methods.empty() ? nullptr : &methods.front().trajectory);
  if (first != nullptr && !first->empty()) {
    const Eigen::Vector3d p0 = first->poses().front().T_world_body.translation();
    const cv::Point2d px = canvas.ToPixel(p0.x(), p0.y());
    cv::circle(canvas.image(), cv::Point(px), 7, cv::Scalar(255, 255, 255), cv::FILLED,
               cv::LINE_AA);
    cv::circle(canvas.image(), cv::Point(px), 7, kBlack, 2, cv::LINE_AA);
  }
  canvas.LegendOutsideRight(legend);
  canvas.DrawAxes("x east [m]", "y north [m]",
                  options.title.empty() ? "Trajectories (top view)" : options.title);
  return SaveCanvas(canvas, png_file);
}

ErrorSeries MakeErrorSeries(const std::string& name, const std::vector<PoseError>& errors,
                            Timestamp reference) {
  ErrorSeries s;
  s.name = name;
  s.time_s.reserve(errors.size());
  s.error_m.reserve(errors.size());
  for (const PoseError& e : errors) {
    s.time_s.push_back(e.stamp.SecondsSince(reference));
    s.error_m.push_back(e.position_error_m);
  }
  return s;
}

Status PlotPositionErrors(const std::vector<ErrorSeries>& series,
                          const std::vector<OutageWindow>& outages,
                          const std::filesystem::path& png_file, const PlotOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  double t_lo = std::numeric_limits<double>::infinity(), t_hi = -t_lo, e_hi = 0.0;
  for (const ErrorSeries& s : series) {
    if (s.time_s.size() != s.error_m.size()) {
      return InvalidArgumentError("PlotPositionErrors: series \"" + s.name + "\" has " +
                                  std::to_string(s.time_s.size()) + " times but " +
                                  std::to_string(s.error_m.size()) + " errors");
    }
    for (size_t i = 0; i < s.time_s.size(); ++i) {
      if (!std::isfinite(s.time_s[i]) || !std::isfinite(s.error_m[i])) continue;
      t_lo = std::min(t_lo, s.time_s[i]);
      t_hi = std::max(t_hi, s.time_s[i]);
      e_hi = std::max(e_hi, s.error_m[i]);
    }
  }
  if (!(t_lo <= t_hi)) return InvalidArgumentError("PlotPositionErrors: no finite sample to draw");
  if (!(e_hi > 0.0)) e_hi = 1.0;

  PlotCanvas canvas(options.width_px, options.height_px);
  canvas.SetRange(t_lo, t_hi, 0.0, e_hi * 1.08, /*equal_aspect=*/false);
  canvas.DrawGrid();
  for (const OutageWindow& w : outages) {
    canvas.ShadeXSpan(w.start_s, w.start_s + w.duration_s, kOutageColor, 0.22);
  }
  std::vector<LegendEntry> legend;
  std::vector<cv::Point2d> all_pts;
  for (size_t i = 0; i < series.size(); ++i) {
    std::vector<cv::Point2d> pts;
    pts.reserve(series[i].time_s.size());
    for (size_t k = 0; k < series[i].time_s.size(); ++k) {
      pts.emplace_back(series[i].time_s[k], series[i].error_m[k]);
    }
    all_pts.insert(all_pts.end(), pts.begin(), pts.end());
    canvas.Polyline(pts, PaletteColor(i), 2);
    legend.push_back({series[i].name, PaletteColor(i), 2, LegendEntry::Kind::kLine});
  }
  if (!outages.empty()) {
    legend.push_back({"GNSS outage", 0.22 * kOutageColor + 0.78 * cv::Scalar(255, 255, 255), 2,
                      LegendEntry::Kind::kBox});
  }
  canvas.LegendAvoiding(legend, all_pts);
  canvas.DrawAxes("time since start [s]", "position error [m]",
                  options.title.empty() ? "Position error over time" : options.title);
  return SaveCanvas(canvas, png_file);
}

Status PlotMapHeight(const PointCloud& map, const std::vector<Eigen::Vector3d>& overlay,
                     const std::filesystem::path& png_file, const PlotOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  Bounds b;
  std::vector<float> heights;
  heights.reserve(map.size());
  for (const Eigen::Vector3f& p : map.points()) {
    if (!p.allFinite()) continue;
    b.Add(p.x(), p.y());
    heights.push_back(p.z());
  }
  if (!b.valid()) return InvalidArgumentError("PlotMapHeight: the map has no finite point");
  b.Pad(0.03, 1.0);

  // Height range: 1st..99th percentile, so a few outliers do not wash out the colours.
  const size_t n = heights.size();
  std::nth_element(heights.begin(), heights.begin() + n / 100, heights.end());
  double z_lo = heights[n / 100];
  std::nth_element(heights.begin(), heights.begin() + (n - 1 - n / 100), heights.end());
  double z_hi = heights[n - 1 - n / 100];
  if (!(z_hi > z_lo)) {
    z_lo -= 0.5;
    z_hi += 0.5;
  }

  const int colorbar_w = 150;
  const cv::Size fig = PlotCanvas::FitEqualAspect(b.x_hi - b.x_lo, b.y_hi - b.y_lo,
                                                  options.width_px, options.height_px, colorbar_w);
  PlotCanvas canvas(fig.width, fig.height, colorbar_w);
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
    canvas.Polyline(pts, kBlack, 2);
  }

  // Colour bar with height ticks.
  const int bar_x = area.br().x + 28, bar_w = 22, bar_y = area.y, bar_h = area.height;
  cv::Mat ramp(bar_h, 1, CV_8U);
  for (int r = 0; r < bar_h; ++r) {
    ramp.at<uint8_t>(r, 0) = static_cast<uint8_t>(
        std::lround(255.0 * (1.0 - static_cast<double>(r) / std::max(1, bar_h - 1))));
  }
  cv::Mat ramp_colored;
  cv::applyColorMap(ramp, ramp_colored, cv::COLORMAP_TURBO);
  cv::resize(ramp_colored, ramp_colored, cv::Size(bar_w, bar_h), 0, 0, cv::INTER_NEAREST);
  ramp_colored.copyTo(canvas.image()(cv::Rect(bar_x, bar_y, bar_w, bar_h)));
  cv::rectangle(canvas.image(), cv::Rect(bar_x, bar_y, bar_w, bar_h), cv::Scalar(60, 60, 60), 1);
  double step = 1.0;
  for (double z : internal::NiceTicks(z_lo, z_hi, 6, &step)) {
    const int y = bar_y + static_cast<int>(std::lround((z_hi - z) / (z_hi - z_lo) * (bar_h - 1)));
    cv::line(canvas.image(), {bar_x + bar_w, y}, {bar_x + bar_w + 5, y}, cv::Scalar(60, 60, 60), 1);
    canvas.Text(internal::FormatTick(z, step), {bar_x + bar_w + 9, y + 6}, 0.5,
                cv::Scalar(60, 60, 60));
  }
  canvas.Text("z [m]", {bar_x - 4, bar_y - 10}, 0.55, kBlack);

  canvas.DrawAxes("x east [m]", "y north [m]",
                  options.title.empty() ? "Map from above, coloured by height" : options.title);
  return SaveCanvas(canvas, png_file);
}

}  // namespace slam_mms::eval
