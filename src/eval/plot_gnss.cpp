// Plot 4 of plots.hpp: the GNSS status per method over time and per submap.

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "eval/plot_canvas.hpp"
#include "slam_mms/eval/plots.hpp"

namespace slam_mms::eval {
namespace {

using internal::kBlackColor;
using internal::kOutageColor;
using internal::LegendEntry;
using internal::PlotCanvas;

// Okabe-Ito bluish green, orange, vermillion (BGR); grey where no GNSS was used.
cv::Scalar StatusColor(GnssAvailability a) {
  switch (a) {
    case GnssAvailability::kValid: return {115, 158, 0};
    case GnssAvailability::kDegraded: return {0, 159, 230};
    case GnssAvailability::kOutage: return {0, 94, 213};
  }
  return {200, 200, 200};
}
const cv::Scalar kNoGnssColor(215, 215, 215);

int Severity(GnssAvailability a) {
  switch (a) {
    case GnssAvailability::kValid: return 0;
    case GnssAvailability::kDegraded: return 1;
    case GnssAvailability::kOutage: return 2;
  }
  return 0;
}

}  // namespace

GnssStatusTrack MakeGnssStatusTrack(const std::string& name,
                                    const std::vector<GnssAvailabilityInterval>& availability,
                                    const std::vector<ScanSubmap>& scans, Timestamp reference) {
  GnssStatusTrack track;
  track.name = name;
  for (const GnssAvailabilityInterval& a : availability) {
    track.spans.push_back(
        {a.start.SecondsSince(reference), a.end.SecondsSince(reference), a.availability});
  }
  for (size_t i = 0; i < scans.size(); ++i) {
    const double t = scans[i].stamp.SecondsSince(reference);
    if (track.submaps.empty() || scans[i].submap_id != track.submaps.back().id) {
      if (!track.submaps.empty()) track.submaps.back().end_s = t;
      track.submaps.push_back({scans[i].submap_id, t, t});
    } else {
      track.submaps.back().end_s = t;
    }
  }
  return track;
}

GnssAvailability WorstGnssStatus(const GnssStatusTrack& track, double start_s, double end_s) {
  GnssAvailability worst = GnssAvailability::kValid;
  for (const GnssStatusTrack::Span& s : track.spans) {
    const bool overlaps = end_s > start_s ? (s.start_s < end_s && s.end_s > start_s)
                                          : (s.start_s <= start_s && start_s < s.end_s);
    if (overlaps && Severity(s.status) > Severity(worst)) worst = s.status;
  }
  return worst;
}

Status PlotGnssStatus(const std::vector<GnssStatusTrack>& tracks,
                      const std::vector<OutageWindow>& outages,
                      const std::filesystem::path& png_file, const PlotOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (tracks.empty()) return InvalidArgumentError("PlotGnssStatus: no track to draw");
  double t_lo = std::numeric_limits<double>::infinity(), t_hi = -t_lo;
  auto add = [&](double t) {
    if (!std::isfinite(t)) return;
    t_lo = std::min(t_lo, t);
    t_hi = std::max(t_hi, t);
  };
  for (const GnssStatusTrack& tr : tracks) {
    for (const auto& s : tr.spans) {
      add(s.start_s);
      add(s.end_s);
    }
    for (const auto& m : tr.submaps) {
      add(m.start_s);
      add(m.end_s);
    }
  }
  if (!(t_lo <= t_hi)) {
    return InvalidArgumentError("PlotGnssStatus: no status interval and no submap to draw");
  }
  if (!(t_hi > t_lo)) t_hi = t_lo + 1.0;
  bool any_outage_window = false;
  for (const OutageWindow& w : outages) {
    any_outage_window = any_outage_window ||
                        (w.duration_s > 0.0 && w.start_s < t_hi && w.start_s + w.duration_s > t_lo);
  }

  // Rows in data units (y down the figure): per track a name line, a time strip, a submap strip.
  constexpr double kName = 0.8, kStrip = 1.0, kGap = 0.25, kTrackGap = 0.45;
  const double track_h = kName + 2 * kStrip + kGap + kTrackGap;
  const double top = any_outage_window ? kStrip + kTrackGap : 0.0;
  const double total = top + tracks.size() * track_h;
  std::vector<LegendEntry> legend = {
      {"available", StatusColor(GnssAvailability::kValid), 2, LegendEntry::Kind::kBox},
      {"degraded", StatusColor(GnssAvailability::kDegraded), 2, LegendEntry::Kind::kBox},
      {"outage", StatusColor(GnssAvailability::kOutage), 2, LegendEntry::Kind::kBox},
      {"no GNSS used", kNoGnssColor, 2, LegendEntry::Kind::kBox}};
  if (any_outage_window) {
    legend.push_back({"requested outage", 0.4 * kOutageColor + 0.6 * cv::Scalar(255, 255, 255), 2,
                      LegendEntry::Kind::kBox});
  }
  const int right_px = PlotCanvas::LegendSize(legend).width + 30;
  const int px_per_unit = 26;
  const int height = std::clamp(
      static_cast<int>(std::ceil(total * px_per_unit)) + PlotCanvas::kTopPx + PlotCanvas::kBottomPx,
      240, std::max(240, options.height_px));
  PlotCanvas canvas(options.width_px, height, right_px);
  canvas.set_y_ticks(false);
  // y up in data: row positions as total - depth.
  canvas.SetRange(t_lo, t_hi, 0.0, total, /*equal_aspect=*/false);
  canvas.DrawGrid();
  auto box = [&](double t0, double t1, double depth0, double depth1, const cv::Scalar& color) {
    const cv::Point2d a = canvas.ToPixel(std::max(t0, t_lo), total - depth0);
    const cv::Point2d b = canvas.ToPixel(std::min(t1, t_hi), total - depth1);
    const cv::Rect r(cv::Point(static_cast<int>(std::lround(a.x)), static_cast<int>(a.y)),
                     cv::Point(static_cast<int>(std::lround(b.x)), static_cast<int>(b.y)));
    const cv::Rect clipped = r & canvas.PlotArea();
    if (clipped.width > 0 && clipped.height > 0) canvas.image()(clipped).setTo(color);
    return clipped;
  };
  auto left_label = [&](const std::string& s, double depth_mid) {
    const cv::Point2d p = canvas.ToPixel(t_lo, total - depth_mid);
    int base = 0;
    const cv::Size sz = cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, 0.48, 1, &base);
    canvas.Text(s, {canvas.PlotArea().x - 8 - sz.width, static_cast<int>(p.y) + sz.height / 2},
                0.48, cv::Scalar(60, 60, 60));
  };
  if (any_outage_window) {
    for (const OutageWindow& w : outages) {
      box(w.start_s, w.start_s + w.duration_s, 0.0, kStrip,
          0.4 * kOutageColor + 0.6 * cv::Scalar(255, 255, 255));
    }
    left_label("requested", 0.5 * kStrip);
  }
  for (size_t i = 0; i < tracks.size(); ++i) {
    const GnssStatusTrack& tr = tracks[i];
    const double d0 = top + i * track_h;
    const cv::Point2d name_px = canvas.ToPixel(t_lo, total - (d0 + kName * 0.8));
    canvas.Text(tr.name, {canvas.PlotArea().x + 4, static_cast<int>(name_px.y)}, 0.55, kBlackColor);
    const double s0 = d0 + kName, s1 = s0 + kStrip + kGap;
    left_label("GNSS", s0 + 0.5 * kStrip);
    left_label("submaps", s1 + 0.5 * kStrip);
    if (tr.spans.empty()) {
      box(t_lo, t_hi, s0, s0 + kStrip, kNoGnssColor);
      box(t_lo, t_hi, s1, s1 + kStrip, kNoGnssColor);
      const cv::Point2d p = canvas.ToPixel(0.5 * (t_lo + t_hi), total - (s0 + 0.75 * kStrip));
      canvas.Text("no GNSS used", {static_cast<int>(p.x) - 50, static_cast<int>(p.y)}, 0.5,
                  cv::Scalar(60, 60, 60));
    } else {
      for (const GnssStatusTrack::Span& s : tr.spans) {
        box(s.start_s, s.end_s, s0, s0 + kStrip, StatusColor(s.status));
      }
    }
    if (tr.submaps.empty()) {
      box(t_lo, t_hi, s1, s1 + kStrip, kNoGnssColor);
      const cv::Point2d p = canvas.ToPixel(0.5 * (t_lo + t_hi), total - (s1 + 0.75 * kStrip));
      canvas.Text("no submaps", {static_cast<int>(p.x) - 45, static_cast<int>(p.y)}, 0.5,
                  cv::Scalar(60, 60, 60));
    }
    for (const GnssStatusTrack::Submap& m : tr.submaps) {
      const GnssAvailability worst = WorstGnssStatus(tr, m.start_s, m.end_s);
      const cv::Rect r = box(m.start_s, std::max(m.end_s, m.start_s + 1e-3), s1, s1 + kStrip,
                             tr.spans.empty() ? kNoGnssColor : StatusColor(worst));
      if (r.width <= 0) continue;
      cv::line(canvas.image(), r.tl(), {r.x, r.br().y - 1}, cv::Scalar(255, 255, 255), 1);
      const std::string id = std::to_string(m.id);
      int base = 0;
      const cv::Size sz = cv::getTextSize(id, cv::FONT_HERSHEY_SIMPLEX, 0.4, 1, &base);
      if (sz.width + 4 < r.width) {
        canvas.Text(id, {r.x + r.width / 2 - sz.width / 2, r.y + r.height / 2 + sz.height / 2}, 0.4,
                    tr.spans.empty() ? cv::Scalar(70, 70, 70) : cv::Scalar(255, 255, 255));
      }
    }
  }
  canvas.LegendOutsideRight(legend);
  canvas.DrawAxes("time since start [s]", "",
                  options.title.empty() ? "GNSS status over time and per submap (worst status)"
                                        : options.title);
  return internal::SavePng(canvas.image(), png_file);
}

}  // namespace slam_mms::eval
