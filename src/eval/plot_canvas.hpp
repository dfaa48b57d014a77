#pragma once
// Private helper of the eval plots: a white figure with one axes box, a data -> pixel mapping,
// "nice" ticks, grid, labels, title and a legend, drawn with OpenCV (anti-aliased).
//
// Thread safety: none; one canvas per thread.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"

namespace slam_mms::eval::internal {

/// GNSS outage marks (orange, BGR) and black.
const cv::Scalar kOutageColor(0, 140, 255);
const cv::Scalar kBlackColor(0, 0, 0);

/// A bounding box of finite data points.
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

/// A colour-blind-friendly qualitative palette (Okabe-Ito), BGR.
cv::Scalar PaletteColor(size_t index);

/// The turbo colour map at u in [0, 1] (clamped), BGR.
cv::Scalar TurboColor(double u);

/// Tick positions covering [lo, hi] at a 1/2/5 x 10^k step giving about `target` ticks.
std::vector<double> NiceTicks(double lo, double hi, int target, double* step_out = nullptr);
/// Tick label text with just enough decimals for `step`.
std::string FormatTick(double value, double step);

/// Text laid out to fit a width (FitText): its lines, font scale and thickness.
struct TextLayout {
  std::vector<std::string> lines;
  double scale = 0.0;
  int thickness = 1;
  int width_px = 0;      // the widest line [px]
  int line_step_px = 0;  // baseline to baseline [px]
};

/// `text` laid out for the Hershey simplex font within `max_width_px`: one line at the largest
/// scale in [0.85 * scale, scale] that fits; else (max_lines >= 2) two lines, broken at the first
/// ": " (dropped) or else at the space that balances them, at the largest scale in [min_scale,
/// min(scale, 0.7)] that fits; else one line at the largest scale down to min_scale. A line still
/// too wide at min_scale is cut and ends in "...". Thickness drops to 1 below scale 0.65.
TextLayout FitText(const std::string& text, int max_width_px, double scale, double min_scale,
                   int thickness, int max_lines);

struct LegendEntry {
  std::string label;
  cv::Scalar color;
  int thickness = 2;
  enum class Kind { kLine, kBox, kDot } kind = Kind::kLine;
};

class PlotCanvas {
 public:
  /// A width x height figure; the axes box leaves room for labels (right margin `right_px` for a
  /// colour bar, if any).
  PlotCanvas(int width_px, int height_px, int right_px = 40);
  /// The same with explicit top and bottom margins (small multiples). Under 56 px of top margin
  /// the title is smaller; under 70 px of bottom margin there is no room for the x label.
  PlotCanvas(int width_px, int height_px, int right_px, int top_px, int bottom_px);

  /// Margins around the axes box [px].
  static constexpr int kLeftPx = 105, kTopPx = 64, kBottomPx = 78;
  /// The title's distance from the figure's left and right edges [px].
  static constexpr int kTitleMarginPx = 14;
  /// The figure size that fits data spanning dx x dy at equal scale inside at most
  /// max_width x max_height (one dimension shrinks; never below 480 x 360).
  static cv::Size FitEqualAspect(double dx, double dy, int max_width_px, int max_height_px,
                                 int right_px = 40);

  /// Sets the data ranges. With `equal_aspect` the ranges are widened so 1 m in x spans as many
  /// pixels as 1 m in y.
  void SetRange(double x_lo, double x_hi, double y_lo, double y_hi, bool equal_aspect);

  cv::Point2d ToPixel(double x, double y) const;
  /// Fixed-point (shift 4) pixel for anti-aliased sub-pixel drawing.
  cv::Point ToPixelFixed(double x, double y) const;
  cv::Rect PlotArea() const { return area_; }
  double PixelsPerUnitX() const { return area_.width / (x_hi_ - x_lo_); }
  double PixelsPerUnitY() const { return area_.height / (y_hi_ - y_lo_); }
  double x_lo() const { return x_lo_; }
  double x_hi() const { return x_hi_; }
  double y_lo() const { return y_lo_; }
  double y_hi() const { return y_hi_; }

  /// Without y ticks, DrawGrid and DrawAxes draw no horizontal grid lines and no y tick labels.
  void set_y_ticks(bool on) { y_ticks_ = on; }

  /// Grid lines and the axes frame (call before drawing data).
  void DrawGrid();
  /// Tick labels, axis labels and the title (call after the data so the frame is on top). An
  /// empty label or title is not drawn. The title stays kTitleMarginPx inside the figure's left
  /// and right edges (FitText: smaller, on two lines with a top margin of kTopPx or more, or
  /// elided).
  void DrawAxes(const std::string& x_label, const std::string& y_label, const std::string& title);

  /// A polyline in data coordinates, clipped to the axes box.
  void Polyline(const std::vector<cv::Point2d>& data_pts, const cv::Scalar& color, int thickness);
  /// Line segments between consecutive `data_pts`, segment i (from point i to i+1) in colours[i]
  /// (colours.size() >= data_pts.size() - 1), clipped to the axes box; NaN points break the line.
  void ColoredPolyline(const std::vector<cv::Point2d>& data_pts,
                       const std::vector<cv::Scalar>& colors, int thickness);
  /// A vertical turbo colour bar at pixel rectangle `bar` for values lo (bottom) .. hi (top), with
  /// ticks and labels right of it and `label` above it.
  void TurboColorBar(const cv::Rect& bar, double lo, double hi, const std::string& label);
  /// A filled rectangle in data x from x0 to x1 over the full y range, alpha-blended.
  void ShadeXSpan(double x0, double x1, const cv::Scalar& color, double alpha);
  /// A legend box in the upper-right (or upper-left) corner of the axes.
  void Legend(const std::vector<LegendEntry>& entries, bool upper_left = false);
  /// A legend box right of the axes box, top-aligned (construct the canvas with right_px >=
  /// LegendSize().width + 24).
  void LegendOutsideRight(const std::vector<LegendEntry>& entries);
  /// Size of the legend box for `entries` [px].
  static cv::Size LegendSize(const std::vector<LegendEntry>& entries);
  /// A legend box in the corner of the axes that covers the fewest of `data_pts` (ties: upper
  /// right, upper left, lower right, lower left).
  void LegendAvoiding(const std::vector<LegendEntry>& entries,
                      const std::vector<cv::Point2d>& data_pts);
  /// Text at a pixel position (baseline-left), anti-aliased.
  void Text(const std::string& s, cv::Point org, double scale, const cv::Scalar& color,
            int thickness = 1);

  cv::Mat& image() { return image_; }
  const cv::Mat& image() const { return image_; }
  /// Writes a PNG; false on failure.
  bool Save(const std::string& path) const;

 private:
  // corner: 0 upper right, 1 upper left, 2 lower right, 3 lower left (inside the axes), 4 outside
  // right of the axes.
  void LegendAt(const std::vector<LegendEntry>& entries, int corner);
  // About one y tick per 40 px of axes height, 2..7.
  int YTickTarget() const;
  // About one x tick per 85 px of axes width, 2..8.
  int XTickTarget() const;

  cv::Mat image_;
  cv::Rect area_;
  int top_px_ = kTopPx;
  bool y_ticks_ = true;
  double x_lo_ = 0, x_hi_ = 1, y_lo_ = 0, y_hi_ = 1;
};

/// Writes `image` as a PNG; NotFound naming the file on failure.
Status SavePng(const cv::Mat& image, const std::filesystem::path& file);

}  // namespace slam_mms::eval::internal
