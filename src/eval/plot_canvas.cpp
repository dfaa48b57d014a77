#include "eval/plot_canvas.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "io/png_file.hpp"

namespace slam_mms::eval::internal {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kShift = 4;  // sub-pixel bits for anti-aliased drawing
constexpr double kShiftScale = 16.0;
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kDarkGray(60, 60, 60);
const cv::Scalar kGridGray(225, 225, 225);

}  // namespace

cv::Scalar PaletteColor(size_t index) {
  // Okabe-Ito: blue, vermillion, bluish green, reddish purple, orange, sky blue, yellow (BGR).
  static const cv::Scalar kColors[] = {cv::Scalar(178, 114, 0), cv::Scalar(0, 94, 213),
                                       cv::Scalar(115, 158, 0), cv::Scalar(167, 121, 204),
                                       cv::Scalar(0, 159, 230), cv::Scalar(233, 180, 86),
                                       cv::Scalar(66, 228, 240)};
  return kColors[index % (sizeof(kColors) / sizeof(kColors[0]))];
}

cv::Scalar TurboColor(double u) {
  static const cv::Mat lut = [] {
    cv::Mat ramp(256, 1, CV_8U);
    for (int i = 0; i < 256; ++i) ramp.at<uint8_t>(i, 0) = static_cast<uint8_t>(i);
    cv::Mat colored;
    cv::applyColorMap(ramp, colored, cv::COLORMAP_TURBO);
    return colored;
  }();
  const double c = std::isfinite(u) ? std::clamp(u, 0.0, 1.0) : 0.0;
  const cv::Vec3b v = lut.at<cv::Vec3b>(static_cast<int>(std::lround(c * 255.0)), 0);
  return cv::Scalar(v[0], v[1], v[2]);
}

std::vector<double> NiceTicks(double lo, double hi, int target, double* step_out) {
  std::vector<double> ticks;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return ticks;
  const double raw = (hi - lo) / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double frac = raw / mag;
  const double nice = frac < 1.5 ? 1.0 : frac < 3.0 ? 2.0 : frac < 7.0 ? 5.0 : 10.0;
  const double step = nice * mag;
  if (step_out != nullptr) *step_out = step;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step) {
    ticks.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
  }
  return ticks;
}

std::string FormatTick(double value, double step) {
  int decimals = 0;
  if (step > 0 && step < 1.0) decimals = static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, value);
  return buf;
}

PlotCanvas::PlotCanvas(int width_px, int height_px, int right_px)
    : image_(height_px, width_px, CV_8UC3, cv::Scalar(255, 255, 255)) {
  area_ = cv::Rect(kLeftPx, kTopPx, std::max(10, width_px - kLeftPx - right_px),
                   std::max(10, height_px - kTopPx - kBottomPx));
}

PlotCanvas::PlotCanvas(int width_px, int height_px, int right_px, int top_px, int bottom_px)
    : image_(height_px, width_px, CV_8UC3, cv::Scalar(255, 255, 255)), top_px_(top_px) {
  area_ = cv::Rect(kLeftPx, top_px, std::max(10, width_px - kLeftPx - right_px),
                   std::max(10, height_px - top_px - bottom_px));
}

int PlotCanvas::YTickTarget() const { return std::clamp(area_.height / 40, 2, 7); }
int PlotCanvas::XTickTarget() const { return std::clamp(area_.width / 85, 2, 8); }

cv::Size PlotCanvas::FitEqualAspect(double dx, double dy, int max_width_px, int max_height_px,
                                    int right_px) {
  const int aw = max_width_px - kLeftPx - right_px;
  const int ah = max_height_px - kTopPx - kBottomPx;
  if (!(dx > 0.0) || !(dy > 0.0) || aw <= 0 || ah <= 0) return {max_width_px, max_height_px};
  const double s = std::min(aw / dx, ah / dy);
  const int w = std::max(480, static_cast<int>(std::ceil(dx * s)) + kLeftPx + right_px);
  const int h = std::max(360, static_cast<int>(std::ceil(dy * s)) + kTopPx + kBottomPx);
  return {std::min(w, max_width_px), std::min(h, max_height_px)};
}

void PlotCanvas::SetRange(double x_lo, double x_hi, double y_lo, double y_hi, bool equal_aspect) {
  if (!(x_hi > x_lo)) {
    x_lo -= 0.5;
    x_hi += 0.5;
  }
  if (!(y_hi > y_lo)) {
    y_lo -= 0.5;
    y_hi += 0.5;
  }
  if (equal_aspect) {
    const double sx = area_.width / (x_hi - x_lo);
    const double sy = area_.height / (y_hi - y_lo);
    const double s = std::min(sx, sy);
    const double cx = 0.5 * (x_lo + x_hi), cy = 0.5 * (y_lo + y_hi);
    const double hx = 0.5 * area_.width / s, hy = 0.5 * area_.height / s;
    x_lo = cx - hx;
    x_hi = cx + hx;
    y_lo = cy - hy;
    y_hi = cy + hy;
  }
  x_lo_ = x_lo;
  x_hi_ = x_hi;
  y_lo_ = y_lo;
  y_hi_ = y_hi;
}

cv::Point2d PlotCanvas::ToPixel(double x, double y) const {
  return {area_.x + (x - x_lo_) / (x_hi_ - x_lo_) * area_.width,
          area_.y + (y_hi_ - y) / (y_hi_ - y_lo_) * area_.height};
}

cv::Point PlotCanvas::ToPixelFixed(double x, double y) const {
  const cv::Point2d p = ToPixel(x, y);
  return {static_cast<int>(std::lround(p.x * kShiftScale)),
          static_cast<int>(std::lround(p.y * kShiftScale))};
}

void PlotCanvas::DrawGrid() {
  cv::Mat roi = image_(area_);
  for (double x : NiceTicks(x_lo_, x_hi_, XTickTarget())) {
    const double px = ToPixel(x, 0).x - area_.x;
    cv::line(roi, cv::Point(static_cast<int>(std::lround(px)), 0),
             cv::Point(static_cast<int>(std::lround(px)), area_.height), kGridGray, 1, cv::LINE_8);
  }
  for (double y : y_ticks_ ? NiceTicks(y_lo_, y_hi_, YTickTarget()) : std::vector<double>()) {
    const double py = ToPixel(0, y).y - area_.y;
    cv::line(roi, cv::Point(0, static_cast<int>(std::lround(py))),
             cv::Point(area_.width, static_cast<int>(std::lround(py))), kGridGray, 1, cv::LINE_8);
  }
}

void PlotCanvas::Text(const std::string& s, cv::Point org, double scale, const cv::Scalar& color,
                      int thickness) {
  cv::putText(image_, s, org, kFont, scale, color, thickness, cv::LINE_AA);
}

void PlotCanvas::DrawAxes(const std::string& x_label, const std::string& y_label,
                          const std::string& title) {
  // White margins hide any data drawn outside the box.
  cv::rectangle(image_, area_, kDarkGray, 1, cv::LINE_8);
  const double tick_scale = 0.52;
  double step = 1.0;
  for (double x : NiceTicks(x_lo_, x_hi_, XTickTarget(), &step)) {
    const int px = static_cast<int>(std::lround(ToPixel(x, 0).x));
    cv::line(image_, {px, area_.br().y}, {px, area_.br().y + 6}, kDarkGray, 1);
    const std::string s = FormatTick(x, step);
    int base = 0;
    const cv::Size sz = cv::getTextSize(s, kFont, tick_scale, 1, &base);
    Text(s, {px - sz.width / 2, area_.br().y + 10 + sz.height}, tick_scale, kDarkGray);
  }
  int max_label_w = 0;
  for (double y :
       y_ticks_ ? NiceTicks(y_lo_, y_hi_, YTickTarget(), &step) : std::vector<double>()) {
    const int py = static_cast<int>(std::lround(ToPixel(0, y).y));
    cv::line(image_, {area_.x - 6, py}, {area_.x, py}, kDarkGray, 1);
    const std::string s = FormatTick(y, step);
    int base = 0;
    const cv::Size sz = cv::getTextSize(s, kFont, tick_scale, 1, &base);
    max_label_w = std::max(max_label_w, sz.width);
    Text(s, {area_.x - 10 - sz.width, py + sz.height / 2}, tick_scale, kDarkGray);
  }
  // Axis labels: x centred below, y rotated to the left of the tick labels.
  const double label_scale = 0.62;
  int base = 0;
  cv::Size sz = cv::getTextSize(x_label, kFont, label_scale, 1, &base);
  if (!x_label.empty()) {
    Text(x_label, {area_.x + area_.width / 2 - sz.width / 2, image_.rows - 18}, label_scale,
         kBlack);
  }
  sz = cv::getTextSize(y_label.empty() ? std::string(" ") : y_label, kFont, label_scale, 1, &base);
  cv::Mat label(sz.height + base + 4, sz.width + 4, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(label, y_label, {2, sz.height + 1}, kFont, label_scale, kBlack, 1, cv::LINE_AA);
  cv::Mat rotated;
  cv::rotate(label, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  const int lx = std::max(2, area_.x - 16 - max_label_w - rotated.cols);
  const int ly = area_.y + area_.height / 2 - rotated.rows / 2;
  if (!y_label.empty() && ly >= 0 && ly + rotated.rows <= image_.rows) {
    rotated.copyTo(image_(cv::Rect(lx, ly, rotated.cols, rotated.rows)));
  }
  // Title: fitted to the figure's width (two lines only with room above the axes), each line
  // centred over the axes and kept kTitleMarginPx inside the figure, the last line's baseline
  // where a one-line title's is.
  if (title.empty()) return;
  const bool small = top_px_ < 56;
  const TextLayout t = FitText(title, image_.cols - 2 * kTitleMarginPx, small ? 0.6 : 0.8,
                               small ? 0.42 : 0.5, small ? 1 : 2, top_px_ >= kTopPx ? 2 : 1);
  const int last_baseline = area_.y - (small ? 9 : 22);
  for (size_t i = 0; i < t.lines.size(); ++i) {
    sz = cv::getTextSize(t.lines[i], kFont, t.scale, t.thickness, &base);
    const int tx = std::max(kTitleMarginPx, std::min(area_.x + area_.width / 2 - sz.width / 2,
                                                     image_.cols - kTitleMarginPx - sz.width));
    const int ty = last_baseline - static_cast<int>(t.lines.size() - 1 - i) * t.line_step_px;
    Text(t.lines[i], {tx, ty}, t.scale, kBlack, t.thickness);
  }
}

namespace {

int TextWidth(const std::string& s, double scale, int thickness) {
  int base = 0;
  return cv::getTextSize(s, kFont, scale, thickness, &base).width;
}

int ThicknessAt(double scale, int thickness) { return scale < 0.65 ? 1 : thickness; }

// The widest of `lines` at `scale`.
int WidestLine(const std::vector<std::string>& lines, double scale, int thickness) {
  int w = 0;
  for (const std::string& l : lines) {
    w = std::max(w, TextWidth(l, scale, ThicknessAt(scale, thickness)));
  }
  return w;
}

// The largest scale in [lo, hi] (steps of 0.02) at which every line fits; < 0 if none.
double LargestFittingScale(const std::vector<std::string>& lines, int max_width_px, double hi,
                           double lo, int thickness) {
  for (double s = hi; s >= lo - 1e-9; s -= 0.02) {
    if (WidestLine(lines, s, thickness) <= max_width_px) return s;
  }
  return -1.0;
}

std::string Trimmed(const std::string& s) {
  const size_t b = s.find_first_not_of(' ');
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(' ') - b + 1);
}

// `s` cut so that it and a trailing "..." fit `max_width_px`.
std::string Elided(const std::string& s, int max_width_px, double scale, int thickness) {
  if (TextWidth(s, scale, thickness) <= max_width_px) return s;
  std::string cut = s;
  while (!cut.empty() && TextWidth(Trimmed(cut) + "...", scale, thickness) > max_width_px) {
    cut.pop_back();
  }
  return Trimmed(cut) + "...";
}

}  // namespace

TextLayout FitText(const std::string& text, int max_width_px, double scale, double min_scale,
                   int thickness, int max_lines) {
  min_scale = std::min(min_scale, scale);
  TextLayout t;
  auto finish = [&](std::vector<std::string> lines, double s) {
    t.scale = s;
    t.thickness = ThicknessAt(s, thickness);
    for (std::string& l : lines) l = Elided(l, max_width_px, s, t.thickness);
    t.lines = std::move(lines);
    t.width_px = WidestLine(t.lines, s, thickness);
    int base = 0;
    t.line_step_px = cv::getTextSize("Ag", kFont, s, t.thickness, &base).height + 7;
    return t;
  };
  // One line, a little smaller at most.
  const std::vector<std::string> one = {text};
  double s =
      LargestFittingScale(one, max_width_px, scale, std::max(min_scale, 0.85 * scale), thickness);
  if (s > 0.0) return finish(one, s);
  // Two lines: at ": ", else at the space that balances the lines best.
  std::vector<std::string> two;
  if (max_lines >= 2) {
    const size_t colon = text.find(": ");
    if (colon != std::string::npos && colon > 0) {
      two = {Trimmed(text.substr(0, colon)), Trimmed(text.substr(colon + 2))};
    }
    const double two_hi = std::min(scale, 0.7);
    if (two.empty() || LargestFittingScale(two, max_width_px, two_hi, min_scale, thickness) < 0.0) {
      int best_w = std::numeric_limits<int>::max();
      for (size_t i = text.find(' '); i != std::string::npos; i = text.find(' ', i + 1)) {
        const std::vector<std::string> cand = {Trimmed(text.substr(0, i)),
                                               Trimmed(text.substr(i + 1))};
        if (cand[0].empty() || cand[1].empty()) continue;
        const int w = WidestLine(cand, min_scale, thickness);
        if (w < best_w) {
          best_w = w;
          two = cand;
        }
      }
    }
    if (!two.empty()) {
      s = LargestFittingScale(two, max_width_px, two_hi, min_scale, thickness);
      if (s > 0.0) return finish(two, s);
    }
  }
  // One line as small as allowed, else elided (two lines elided where they were found).
  s = LargestFittingScale(one, max_width_px, scale, min_scale, thickness);
  if (s > 0.0) return finish(one, s);
  return finish(two.empty() ? one : two, min_scale);
}

void PlotCanvas::Polyline(const std::vector<cv::Point2d>& data_pts, const cv::Scalar& color,
                          int thickness) {
  cv::Mat roi = image_(area_);
  std::vector<cv::Point> run;
  run.reserve(data_pts.size());
  const cv::Point offset(static_cast<int>(area_.x * kShiftScale),
                         static_cast<int>(area_.y * kShiftScale));
  auto flush = [&]() {
    if (run.size() >= 2) {
      cv::polylines(roi, run, false, color, thickness, cv::LINE_AA, kShift);
    } else if (run.size() == 1) {
      cv::circle(roi, run[0], static_cast<int>(thickness * kShiftScale / 2), color, cv::FILLED,
                 cv::LINE_AA, kShift);
    }
    run.clear();
  };
  for (const cv::Point2d& p : data_pts) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
      flush();
      continue;
    }
    run.push_back(ToPixelFixed(p.x, p.y) - offset);
  }
  flush();
}

void PlotCanvas::ColoredPolyline(const std::vector<cv::Point2d>& data_pts,
                                 const std::vector<cv::Scalar>& colors, int thickness) {
  cv::Mat roi = image_(area_);
  const cv::Point offset(static_cast<int>(area_.x * kShiftScale),
                         static_cast<int>(area_.y * kShiftScale));
  for (size_t i = 0; i + 1 < data_pts.size() && i < colors.size(); ++i) {
    const cv::Point2d& a = data_pts[i];
    const cv::Point2d& b = data_pts[i + 1];
    if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y)) {
      continue;
    }
    cv::line(roi, ToPixelFixed(a.x, a.y) - offset, ToPixelFixed(b.x, b.y) - offset, colors[i],
             thickness, cv::LINE_AA, kShift);
  }
}

void PlotCanvas::TurboColorBar(const cv::Rect& bar, double lo, double hi,
                               const std::string& label) {
  const cv::Rect inside = bar & cv::Rect(0, 0, image_.cols, image_.rows);
  if (inside.height < 2 || inside.width < 1) return;
  for (int r = 0; r < inside.height; ++r) {
    const double u = 1.0 - static_cast<double>(r) / (inside.height - 1);
    image_(cv::Rect(inside.x, inside.y + r, inside.width, 1)).setTo(TurboColor(u));
  }
  cv::rectangle(image_, inside, kDarkGray, 1);
  if (!(hi > lo)) hi = lo + 1.0;
  double step = 1.0;
  for (double v : NiceTicks(lo, hi, std::max(2, inside.height / 60), &step)) {
    const int y =
        inside.y + static_cast<int>(std::lround((hi - v) / (hi - lo) * (inside.height - 1)));
    cv::line(image_, {inside.br().x, y}, {inside.br().x + 5, y}, kDarkGray, 1);
    Text(FormatTick(v, step), {inside.br().x + 9, y + 6}, 0.5, kDarkGray);
  }
  Text(label, {inside.x - 4, inside.y - 10}, 0.55, kBlack);
}

void PlotCanvas::ShadeXSpan(double x0, double x1, const cv::Scalar& color, double alpha) {
  const int px0 =
      std::clamp(static_cast<int>(std::lround(ToPixel(x0, 0).x)), area_.x, area_.br().x);
  const int px1 =
      std::clamp(static_cast<int>(std::lround(ToPixel(x1, 0).x)), area_.x, area_.br().x);
  if (px1 <= px0) return;
  cv::Mat roi = image_(cv::Rect(px0, area_.y, px1 - px0, area_.height));
  cv::Mat fill(roi.size(), roi.type(), color);
  cv::addWeighted(fill, alpha, roi, 1.0 - alpha, 0.0, roi);
}

cv::Size PlotCanvas::LegendSize(const std::vector<LegendEntry>& entries) {
  int base = 0, text_w = 0, text_h = 0;
  for (const LegendEntry& e : entries) {
    const cv::Size sz = cv::getTextSize(e.label, kFont, 0.55, 1, &base);
    text_w = std::max(text_w, sz.width);
    text_h = std::max(text_h, sz.height);
  }
  const int row_h = text_h + 14;
  return {10 + 36 + 10 + text_w + 10, 10 + static_cast<int>(entries.size()) * row_h + 5};
}

void PlotCanvas::LegendOutsideRight(const std::vector<LegendEntry>& entries) {
  LegendAt(entries, 4);
}

void PlotCanvas::Legend(const std::vector<LegendEntry>& entries, bool upper_left) {
  LegendAt(entries, upper_left ? 1 : 0);
}

void PlotCanvas::LegendAvoiding(const std::vector<LegendEntry>& entries,
                                const std::vector<cv::Point2d>& data_pts) {
  if (entries.empty()) return;
  const cv::Size sz = LegendSize(entries);
  int best = 0;
  size_t best_count = std::numeric_limits<size_t>::max();
  for (int corner = 0; corner < 4; ++corner) {
    const int x = (corner == 1 || corner == 3) ? area_.x + 12 : area_.br().x - 12 - sz.width;
    const int y = corner < 2 ? area_.y + 12 : area_.br().y - 12 - sz.height;
    const cv::Rect2d box(x - 8, y - 8, sz.width + 16, sz.height + 16);
    size_t count = 0;
    for (const cv::Point2d& p : data_pts) {
      if (std::isfinite(p.x) && box.contains(ToPixel(p.x, p.y))) ++count;
    }
    if (count < best_count) {
      best_count = count;
      best = corner;
    }
  }
  LegendAt(entries, best);
}

void PlotCanvas::LegendAt(const std::vector<LegendEntry>& entries, int corner) {
  if (entries.empty()) return;
  const double scale = 0.55;
  int base = 0, text_h = 0;
  for (const LegendEntry& e : entries) {
    text_h = std::max(text_h, cv::getTextSize(e.label, kFont, scale, 1, &base).height);
  }
  const cv::Size sz = LegendSize(entries);
  const int row_h = text_h + 14, swatch_w = 36, pad = 10;
  const int w = sz.width, h = sz.height;
  int x = (corner == 1 || corner == 3) ? area_.x + 12 : area_.br().x - 12 - w;
  int y = (corner < 2 || corner == 4) ? area_.y + 12 : area_.br().y - 12 - h;
  if (corner == 4) {
    x = area_.br().x + 14;
    y = area_.y;
  }
  cv::Mat roi = image_(cv::Rect(x, y, w, h) & cv::Rect(0, 0, image_.cols, image_.rows));
  cv::Mat white(roi.size(), roi.type(), cv::Scalar(255, 255, 255));
  cv::addWeighted(white, 0.88, roi, 0.12, 0.0, roi);
  cv::rectangle(image_, cv::Rect(x, y, w, h), cv::Scalar(170, 170, 170), 1, cv::LINE_8);
  for (size_t i = 0; i < entries.size(); ++i) {
    const LegendEntry& e = entries[i];
    const int cy = y + pad + static_cast<int>(i) * row_h + row_h / 2;
    const int sx = x + pad;
    switch (e.kind) {
      case LegendEntry::Kind::kLine:
        cv::line(image_, {sx, cy}, {sx + swatch_w, cy}, e.color, e.thickness, cv::LINE_AA);
        break;
      case LegendEntry::Kind::kBox:
        cv::rectangle(image_, cv::Rect(sx, cy - text_h / 2 - 2, swatch_w, text_h + 4), e.color,
                      cv::FILLED);
        break;
      case LegendEntry::Kind::kDot:
        cv::circle(image_, {sx + swatch_w / 2, cy}, 5, e.color, cv::FILLED, cv::LINE_AA);
        break;
    }
    Text(e.label, {sx + swatch_w + 10, cy + text_h / 2}, scale, kBlack);
  }
}

Status SavePng(const cv::Mat& image, const std::filesystem::path& file) {
  if (image.depth() != CV_8U) {
    return InvalidArgumentError("cannot write PNG " + file.string() + ": not an 8-bit image");
  }
  return io_internal::WritePng(file, image.ptr<uint8_t>(0), image.cols, image.rows,
                               image.channels(), image.step[0]);
}

bool PlotCanvas::Save(const std::string& path) const { return SavePng(image_, path).ok(); }

}  // namespace slam_mms::eval::internal
