#pragma once
// Private helper of the eval plots: a white figure with one axes box, a data -> pixel mapping,
// "nice" ticks, grid, labels, title and a legend, drawn with OpenCV (anti-aliased).
//
// Thread safety: none; one canvas per thread.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace slam_mms::eval::internal {

/// A colour-blind-friendly qualitative palette (Okabe-Ito), BGR.
cv::Scalar PaletteColor(size_t index);

/// Tick positions covering [lo, hi] at a 1/2/5 x 10^k step giving about `target` ticks.
std::vector<double> NiceTicks(double lo, double hi, int target, double* step_out = nullptr);
/// Tick label text with just enough decimals for `step`.
std::string FormatTick(double value, double step);

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

  /// Margins around the axes box [px].
  static constexpr int kLeftPx = 105, kTopPx = 64, kBottomPx = 78;
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

  /// Grid lines and the axes frame (call before drawing data).
  void DrawGrid();
  /// Tick labels, axis labels and the title (call after the data so the frame is on top).
  void DrawAxes(const std::string& x_label, const std::string& y_label, const std::string& title);

  /// A polyline in data coordinates, clipped to the axes box.
  void Polyline(const std::vector<cv::Point2d>& data_pts, const cv::Scalar& color, int thickness);
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
  /// Writes a PNG; false on failure.
  bool Save(const std::string& path) const;

 private:
  // corner: 0 upper right, 1 upper left, 2 lower right, 3 lower left (inside the axes), 4 outside
  // right of the axes.
  void LegendAt(const std::vector<LegendEntry>& entries, int corner);

  cv::Mat image_;
  cv::Rect area_;
  double x_lo_ = 0, x_hi_ = 1, y_lo_ = 0, y_hi_ = 1;
};

}  // namespace slam_mms::eval::internal
