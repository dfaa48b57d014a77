// Plot 1 of plots.hpp: trajectories from above, one panel per method coloured by its error, and a
// zoom panel around the focus method's largest error.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "eval/plot_canvas.hpp"
#include "slam_mms/eval/plots.hpp"
#include "slam_mms/eval/trajectory_error.hpp"

namespace slam_mms::eval {
namespace {

using internal::Bounds;
using internal::kBlackColor;
using internal::kOutageColor;
using internal::LegendEntry;
using internal::PaletteColor;
using internal::PlotCanvas;

constexpr int kFigureTitlePx = 46;     // band above the panels for the figure title
constexpr int kColorBarRightPx = 104;  // right margin of a method panel (colour bar + labels)
constexpr int kVerticalMarginPx = PlotCanvas::kTopPx + PlotCanvas::kBottomPx;

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

bool AnyFinite(const std::vector<cv::Point2d>& pts) {
  return std::any_of(pts.begin(), pts.end(),
                     [](const cv::Point2d& p) { return std::isfinite(p.x) && std::isfinite(p.y); });
}

// Draws `pts` with the given thickness on a copy and blends it in (translucent band).
void TranslucentPolyline(PlotCanvas& canvas, const std::vector<cv::Point2d>& pts,
                         const cv::Scalar& color, int thickness, double alpha) {
  cv::Mat before = canvas.image().clone();
  canvas.Polyline(pts, color, thickness);
  cv::addWeighted(canvas.image(), alpha, before, 1.0 - alpha, 0.0, canvas.image());
}

void StartMarker(PlotCanvas& canvas, const Trajectory& t) {
  if (t.empty()) return;
  const Eigen::Vector3d p0 = t.poses().front().T_world_body.translation();
  const cv::Point2d px = canvas.ToPixel(p0.x(), p0.y());
  if (!canvas.PlotArea().contains(cv::Point(px))) return;
  cv::circle(canvas.image(), cv::Point(px), 7, cv::Scalar(255, 255, 255), cv::FILLED, cv::LINE_AA);
  cv::circle(canvas.image(), cv::Point(px), 7, kBlackColor, 2, cv::LINE_AA);
}

std::string Metres(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), v < 0.1 ? "%.3f m" : v < 10.0 ? "%.2f m" : "%.1f m", v);
  return buf;
}

// One method's positions matched to the ground truth and their errors.
struct MethodErrors {
  bool valid = false;
  std::vector<cv::Point2d> est_xy, gt_xy;
  std::vector<double> error_m;
  std::vector<Timestamp> stamps;
  double rms_m = 0.0, max_m = 0.0;
  size_t worst = 0;
};

MethodErrors ErrorsOf(const Trajectory& method, const Trajectory& gt) {
  MethodErrors e;
  if (method.empty() || gt.size() < 2) return e;
  const StatusOr<AteResult> ate = ComputeAte(method, gt);
  if (!ate.ok() || ate->errors.empty()) return e;
  double sum_sq = 0.0;
  for (const PoseError& pe : ate->errors) {
    if (!std::isfinite(pe.position_error_m)) continue;
    e.est_xy.emplace_back(pe.p_est_world.x(), pe.p_est_world.y());
    e.gt_xy.emplace_back(pe.p_gt_world.x(), pe.p_gt_world.y());
    e.error_m.push_back(pe.position_error_m);
    e.stamps.push_back(pe.stamp);
    sum_sq += pe.position_error_m * pe.position_error_m;
    if (pe.position_error_m > e.max_m || e.error_m.size() == 1) {
      e.max_m = pe.position_error_m;
      e.worst = e.error_m.size() - 1;
    }
  }
  if (e.error_m.empty()) return e;
  e.rms_m = std::sqrt(sum_sq / e.error_m.size());
  e.valid = true;
  return e;
}

// The colour scale of a method panel: 0 .. its largest error, rounded up to a readable value.
double ColorScaleMax(const MethodErrors& e) {
  if (!(e.max_m > 0.0)) return 0.01;
  double step = 1.0;
  const std::vector<double> ticks = internal::NiceTicks(0.0, e.max_m, 5, &step);
  return std::max(e.max_m, ticks.empty() ? e.max_m : std::ceil(e.max_m / step - 1e-9) * step);
}

struct Layout {
  int cols = 1, rows = 1, panel_w = 0, panel_h = 0;
};

// The grid of `n` equal panels inside width x max_height that shows the data (dx x dy at equal
// scale) largest.
Layout ChooseLayout(int n, double dx, double dy, int width, int max_height) {
  Layout best;
  double best_scale = -1.0;
  for (int cols = 1; cols <= n; ++cols) {
    const int rows = (n + cols - 1) / cols;
    const int pw = width / cols;
    const int ph = (max_height - kFigureTitlePx) / rows;
    const int aw = pw - PlotCanvas::kLeftPx - kColorBarRightPx;
    const int ah = ph - kVerticalMarginPx;
    if (aw < 60 || ah < 40) continue;
    const double scale = std::min(aw / dx, ah / dy);
    if (scale > best_scale * 1.0001) {
      best_scale = scale;
      best = {cols, rows, pw, ph};
    }
  }
  if (best_scale < 0.0) {
    // Too many panels for the figure: one column, as tall as allowed.
    best = {1, n, width, std::max(kVerticalMarginPx + 40, (max_height - kFigureTitlePx) / n)};
    return best;
  }
  // Shrink the panels' height to the data's aspect (never below 260 px or what fits).
  const int aw = best.panel_w - PlotCanvas::kLeftPx - kColorBarRightPx;
  const double scale = std::min(aw / dx, (best.panel_h - kVerticalMarginPx) / dy);
  const int needed = static_cast<int>(std::ceil(dy * scale)) + kVerticalMarginPx;
  best.panel_h = std::min(best.panel_h, std::max(needed, 260));
  return best;
}

// The single-panel plot in palette colours (no ground truth to colour the errors by).
Status PlotPlain(const NamedTrajectory& ground_truth, const std::vector<NamedTrajectory>& methods,
                 const std::vector<OutageWindow>& outages, Timestamp outage_reference,
                 const Bounds& b, const std::filesystem::path& png_file,
                 const PlotOptions& options) {
  const bool has_gt = !ground_truth.trajectory.empty();
  std::vector<LegendEntry> legend;
  if (has_gt) legend.push_back({ground_truth.name, kBlackColor, 2, LegendEntry::Kind::kLine});
  for (size_t i = 0; i < methods.size(); ++i) {
    legend.push_back({methods[i].name, PaletteColor(i), 2, LegendEntry::Kind::kLine});
  }
  bool any_outage = false;
  for (const NamedTrajectory& m : methods) {
    any_outage = any_outage || AnyFinite(InsideOutages(m.trajectory, outages, outage_reference));
  }
  if (any_outage) {
    legend.push_back({"GNSS outage", 0.35 * kOutageColor + 0.65 * cv::Scalar(255, 255, 255), 10,
                      LegendEntry::Kind::kLine});
  }
  legend.push_back({"start", kBlackColor, 2, LegendEntry::Kind::kDot});
  const int right_px = PlotCanvas::LegendSize(legend).width + 40;
  const cv::Size fig = PlotCanvas::FitEqualAspect(b.x_hi - b.x_lo, b.y_hi - b.y_lo,
                                                  options.width_px, options.height_px, right_px);
  PlotCanvas canvas(fig.width, fig.height, right_px);
  canvas.SetRange(b.x_lo, b.x_hi, b.y_lo, b.y_hi, /*equal_aspect=*/true);
  canvas.DrawGrid();
  if (has_gt && any_outage) {
    TranslucentPolyline(canvas, InsideOutages(ground_truth.trajectory, outages, outage_reference),
                        kOutageColor, 16, 0.35);
  }
  if (has_gt) canvas.Polyline(XY(ground_truth.trajectory), kBlackColor, 2);
  for (size_t i = 0; i < methods.size(); ++i) {
    canvas.Polyline(XY(methods[i].trajectory), PaletteColor(i), 2);
    if (any_outage) {
      canvas.Polyline(InsideOutages(methods[i].trajectory, outages, outage_reference),
                      PaletteColor(i), 5);
    }
  }
  StartMarker(canvas, has_gt ? ground_truth.trajectory
                             : (methods.empty() ? Trajectory() : methods.front().trajectory));
  canvas.LegendOutsideRight(legend);
  canvas.DrawAxes("x east [m]", "y north [m]",
                  options.title.empty() ? "Trajectories (top view)" : options.title);
  return internal::SavePng(canvas.image(), png_file);
}

}  // namespace

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

  std::vector<MethodErrors> errors;
  int focus = -1;
  for (size_t i = 0; i < methods.size(); ++i) {
    errors.push_back(ErrorsOf(methods[i].trajectory, ground_truth.trajectory));
  }
  for (size_t i = 0; i < methods.size() && focus < 0; ++i) {
    if (errors[i].valid && methods[i].name == options.focus_method) focus = static_cast<int>(i);
  }
  for (size_t i = 0; i < methods.size() && focus < 0; ++i) {
    if (errors[i].valid) focus = static_cast<int>(i);
  }
  if (focus < 0) {
    return PlotPlain(ground_truth, methods, outages, outage_reference, b, png_file, options);
  }

  const int num_panels = static_cast<int>(methods.size()) + 1;
  const Layout layout = ChooseLayout(num_panels, b.x_hi - b.x_lo, b.y_hi - b.y_lo, options.width_px,
                                     options.height_px);
  cv::Mat figure(kFigureTitlePx + layout.rows * layout.panel_h, layout.cols * layout.panel_w,
                 CV_8UC3, cv::Scalar(255, 255, 255));
  // The zoom panel (the last) also takes the empty cells of the last row.
  const int zoom_cells = layout.cols * layout.rows - num_panels + 1;
  const int zoom_w = zoom_cells * layout.panel_w;
  auto place = [&](const PlotCanvas& canvas, int index) {
    const int r = index / layout.cols, c = index % layout.cols;
    canvas.image().copyTo(figure(cv::Rect(c * layout.panel_w, kFigureTitlePx + r * layout.panel_h,
                                          canvas.image().cols, layout.panel_h)));
  };

  const std::vector<cv::Point2d> gt_xy = XY(ground_truth.trajectory);
  const std::vector<cv::Point2d> gt_outage =
      InsideOutages(ground_truth.trajectory, outages, outage_reference);
  const bool gt_outage_shown = AnyFinite(gt_outage);

  // The zoom window: around the focus method's largest error, a few times that error wide.
  const MethodErrors& fe = errors[focus];
  const cv::Point2d worst_est = fe.est_xy[fe.worst], worst_gt = fe.gt_xy[fe.worst];
  const cv::Point2d zoom_center = 0.5 * (worst_est + worst_gt);
  const double zoom_radius = std::max(0.5, 3.0 * fe.max_m);

  // The zoom panel's legend sits right of its axes: room for the widest labels.
  std::vector<LegendEntry> widest = {{ground_truth.name, kBlackColor, 2, LegendEntry::Kind::kLine},
                                     {"GNSS outage", kBlackColor, 2, LegendEntry::Kind::kLine}};
  for (const NamedTrajectory& m : methods) {
    widest.push_back({m.name + " (outside the zoom)", kBlackColor, 2, LegendEntry::Kind::kLine});
  }
  widest.push_back(
      {methods[focus].name + ": error vectors", kBlackColor, 2, LegendEntry::Kind::kLine});
  const int zoom_right_px = PlotCanvas::LegendSize(widest).width + 30;

  // Method panels.
  double zoom_x_lo = 0, zoom_x_hi = 0, zoom_y_lo = 0, zoom_y_hi = 0;
  {
    // The zoom panel's range (computed once to outline it on the focus panel).
    PlotCanvas zoom(zoom_w, layout.panel_h, zoom_right_px);
    zoom.SetRange(zoom_center.x - zoom_radius, zoom_center.x + zoom_radius,
                  zoom_center.y - zoom_radius, zoom_center.y + zoom_radius, true);
    zoom_x_lo = zoom.x_lo();
    zoom_x_hi = zoom.x_hi();
    zoom_y_lo = zoom.y_lo();
    zoom_y_hi = zoom.y_hi();
  }
  bool any_outage_shown = false;
  for (size_t i = 0; i < methods.size(); ++i) {
    PlotCanvas canvas(layout.panel_w, layout.panel_h, kColorBarRightPx);
    canvas.SetRange(b.x_lo, b.x_hi, b.y_lo, b.y_hi, /*equal_aspect=*/true);
    canvas.DrawGrid();
    const MethodErrors& e = errors[i];
    // Outages: an orange band under the ground truth, drawn only when some pose lies inside.
    const bool outage_shown =
        gt_outage_shown ||
        AnyFinite(InsideOutages(methods[i].trajectory, outages, outage_reference));
    if (outage_shown) {
      TranslucentPolyline(canvas,
                          gt_outage_shown
                              ? gt_outage
                              : InsideOutages(methods[i].trajectory, outages, outage_reference),
                          kOutageColor, 16, 0.35);
    }
    // The whole estimate thin and grey (also the parts without ground truth), then the matched
    // part coloured by error, the ground truth thin and black on top.
    canvas.Polyline(XY(methods[i].trajectory), cv::Scalar(150, 150, 150), 1);
    std::string title = methods[i].name;
    double scale_max = 0.0;
    if (e.valid) {
      scale_max = ColorScaleMax(e);
      std::vector<cv::Scalar> colors;
      colors.reserve(e.error_m.size());
      for (size_t k = 0; k + 1 < e.error_m.size(); ++k) {
        colors.push_back(
            internal::TurboColor(std::max(e.error_m[k], e.error_m[k + 1]) / scale_max));
      }
      canvas.ColoredPolyline(e.est_xy, colors, 4);
      title += ": RMS " + Metres(e.rms_m) + ", max " + Metres(e.max_m);
    } else {
      canvas.Polyline(XY(methods[i].trajectory), PaletteColor(i), 3);
      title += ": no pose matched to the ground truth";
    }
    if (!gt_xy.empty()) canvas.Polyline(gt_xy, kBlackColor, 1);
    StartMarker(canvas,
                ground_truth.trajectory.empty() ? methods[i].trajectory : ground_truth.trajectory);
    if (static_cast<int>(i) == focus) {
      const cv::Point2d a = canvas.ToPixel(zoom_x_lo, zoom_y_hi);
      const cv::Point2d c = canvas.ToPixel(zoom_x_hi, zoom_y_lo);
      cv::Rect box{cv::Point(a), cv::Point(c)};
      // At least 12 px so it stays visible on a long drive.
      const cv::Point mid = (box.tl() + box.br()) / 2;
      box = cv::Rect(mid.x - std::max(6, box.width / 2), mid.y - std::max(6, box.height / 2),
                     std::max(12, box.width), std::max(12, box.height));
      cv::rectangle(canvas.image(), box & canvas.PlotArea(), kBlackColor, 2, cv::LINE_AA);
      canvas.Text("zoom", {box.x, std::max(canvas.PlotArea().y + 14, box.y - 6)}, 0.5, kBlackColor);
    }
    any_outage_shown = any_outage_shown || outage_shown;
    if (e.valid) {
      const cv::Rect area = canvas.PlotArea();
      canvas.TurboColorBar(cv::Rect(area.br().x + 18, area.y + 8, 18, area.height - 8), 0.0,
                           scale_max, "error [m]");
    }
    canvas.DrawAxes("x east [m]", "y north [m]", title);
    place(canvas, static_cast<int>(i));
  }

  // The zoom panel: the ground truth and every method around the worst error, in palette colours,
  // with the focus method's error vectors (estimate -> ground truth at the same time).
  {
    PlotCanvas zoom(zoom_w, layout.panel_h, zoom_right_px);
    zoom.SetRange(zoom_x_lo, zoom_x_hi, zoom_y_lo, zoom_y_hi, false);
    zoom.DrawGrid();
    if (gt_outage_shown) TranslucentPolyline(zoom, gt_outage, kOutageColor, 24, 0.35);
    const cv::Rect2d window(zoom_x_lo, zoom_y_lo, zoom_x_hi - zoom_x_lo, zoom_y_hi - zoom_y_lo);
    auto dots = [&](const std::vector<cv::Point2d>& pts, const cv::Scalar& color, int radius) {
      for (const cv::Point2d& p : pts) {
        if (!window.contains(p)) continue;
        cv::circle(zoom.image(), cv::Point(zoom.ToPixel(p.x, p.y)), radius, color, cv::FILLED,
                   cv::LINE_AA);
      }
    };
    for (size_t k = 0; k < fe.est_xy.size(); ++k) {
      if (!window.contains(fe.est_xy[k]) && !window.contains(fe.gt_xy[k])) continue;
      zoom.Polyline({fe.est_xy[k], fe.gt_xy[k]},
                    0.5 * PaletteColor(focus) + cv::Scalar(127, 127, 127), 1);
    }
    zoom.Polyline(gt_xy, kBlackColor, 2);
    dots(gt_xy, kBlackColor, 3);
    std::vector<LegendEntry> legend = {
        {ground_truth.name, kBlackColor, 2, LegendEntry::Kind::kLine}};
    // The focus method drawn last (on top); the legend keeps the methods' order.
    for (size_t j = 0; j < methods.size(); ++j) {
      const size_t i =
          j + 1 == methods.size() ? focus : (j < static_cast<size_t>(focus) ? j : j + 1);
      const std::vector<cv::Point2d> pts = XY(methods[i].trajectory);
      zoom.Polyline(pts, PaletteColor(i), 2);
      dots(pts, PaletteColor(i), 3);
    }
    for (size_t i = 0; i < methods.size(); ++i) {
      const std::vector<cv::Point2d> pts = XY(methods[i].trajectory);
      const bool inside = std::any_of(pts.begin(), pts.end(),
                                      [&](const cv::Point2d& p) { return window.contains(p); });
      legend.push_back({methods[i].name + (inside ? "" : " (outside the zoom)"), PaletteColor(i), 2,
                        LegendEntry::Kind::kLine});
    }
    legend.push_back({methods[focus].name + ": error vectors",
                      0.5 * PaletteColor(focus) + cv::Scalar(127, 127, 127), 1,
                      LegendEntry::Kind::kLine});
    if (any_outage_shown) {
      legend.push_back({"GNSS outage", 0.35 * kOutageColor + 0.65 * cv::Scalar(255, 255, 255), 10,
                        LegendEntry::Kind::kLine});
    }
    // The worst pose ringed.
    const cv::Point2d wp = zoom.ToPixel(worst_est.x, worst_est.y);
    cv::circle(zoom.image(), cv::Point(wp), 10, kBlackColor, 2, cv::LINE_AA);
    zoom.LegendOutsideRight(legend);
    char title[256];
    std::snprintf(title, sizeof(title), "Zoom: largest error of %s, %s at t = %.1f s",
                  methods[focus].name.c_str(), Metres(fe.max_m).c_str(),
                  fe.stamps[fe.worst].SecondsSince(outage_reference));
    zoom.DrawAxes("x east [m]", "y north [m]", title);
    place(zoom, num_panels - 1);
  }

  const std::string title =
      options.title.empty() ? "Trajectories from above, coloured by position error" : options.title;
  // One line, smaller or elided where the figure is narrow.
  const internal::TextLayout t = internal::FitText(
      title, figure.cols - 2 * PlotCanvas::kTitleMarginPx, 0.9, 0.5, 2, /*max_lines=*/1);
  cv::putText(figure, t.lines.front(),
              {std::max(PlotCanvas::kTitleMarginPx, figure.cols / 2 - t.width_px / 2), 32},
              cv::FONT_HERSHEY_SIMPLEX, t.scale, kBlackColor, t.thickness, cv::LINE_AA);
  return internal::SavePng(figure, png_file);
}

}  // namespace slam_mms::eval
