#pragma once
// PNG plots of the evaluation report, drawn with OpenCV (no plotting library):
//   1. PlotTrajectoriesTopView: seen from above (x east, y north, equal scale, metre axes), one
//      panel per method (small multiples, so methods never hide each other) with the method
//      coloured by its position error against the ground truth (turbo colour map, a colour bar in
//      metres per panel) over the ground truth in black, and a zoom panel: a window around the
//      largest error of the focus method showing the ground truth and every method there, at a
//      scale where their differences are visible; the focus panel outlines the window. The parts
//      inside GNSS-outage windows lie on an orange band, drawn only when an outage covers some
//      pose. Without a ground truth (or no pose matched in time) one panel shows the methods in
//      their palette colours.
//   2. PlotPositionErrors: horizontal and signed vertical position error over time, one row per
//      method (its own y scale, so a drifting method does not squash the others), columns
//      horizontal | vertical (one 3-D column for series without the components). GNSS outage
//      windows are shaded, and " (GNSS outages shaded)" is appended to the title (a caller's own
//      is dropped), only when a window overlaps the plotted time.
//   3. PlotMapHeight: a map seen from above, each pixel coloured by the height of its highest point
//      (turbo colour map, clipped to the 1st..99th height percentile), with a colour bar, metre
//      axes and an optional trajectory overlay; a line under the title states the clipping
//      ("colours clipped to the 1st..99th percentile: -1.2..4.8 m; data -1.5..6.1 m") and the bar's
//      ends are marked when data lie beyond them.
//   4. PlotGnssStatus: per method, the GNSS status over time (available, degraded, outage) and per
//      submap (the worst status during the submap), with the requested outage windows outlined.
// Colours follow the Okabe-Ito palette in the order the methods are given; the ground truth is
// black. Failures (bad options, nothing to draw, an unwritable path) are Status values.
//
// Thread safety: free functions; safe to call concurrently for distinct output files.

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/eval/outage_error.hpp"
#include "slam_mms/ins/gnss_prior.hpp"

namespace slam_mms::eval {

struct PlotOptions {
  int width_px = 1400;
  int height_px = 1050;
  std::string title;  ///< Empty: a default title per plot.
  /// PlotTrajectoriesTopView: the method whose largest error the zoom panel shows (empty or not
  /// found: the first method).
  std::string focus_method;

  [[nodiscard]] Status Validate() const;
};

struct NamedTrajectory {
  std::string name;
  Trajectory trajectory;
};

/// Plot 1. `outage_reference` is the time the windows are relative to.
Status PlotTrajectoriesTopView(const NamedTrajectory& ground_truth,
                               const std::vector<NamedTrajectory>& methods,
                               const std::vector<OutageWindow>& outages, Timestamp outage_reference,
                               const std::filesystem::path& png_file,
                               const PlotOptions& options = PlotOptions());

/// One method's error samples for plot 2: time relative to the reference [s] and error [m].
struct ErrorSeries {
  std::string name;
  std::vector<double> time_s;
  std::vector<double> error_m;  ///< |p_est - p_gt| [m].
  /// Optional components (empty, or as many as time_s): horizontal |(p_est - p_gt).xy| [m] and
  /// vertical (p_est - p_gt).z [m], up positive. Without them the plot shows error_m only.
  std::vector<double> horizontal_m;
  std::vector<double> vertical_m;
};

/// Builds an ErrorSeries (with the components) from per-pose errors (AteResult::errors).
ErrorSeries MakeErrorSeries(const std::string& name, const std::vector<PoseError>& errors,
                            Timestamp reference);

/// Plot 2. Outage windows are in the same time base as the series.
Status PlotPositionErrors(const std::vector<ErrorSeries>& series,
                          const std::vector<OutageWindow>& outages,
                          const std::filesystem::path& png_file,
                          const PlotOptions& options = PlotOptions());

/// The colour range of plot 3: the 1st..99th height percentile, and the data's full range.
struct HeightColorRange {
  double color_lo_m = 0.0, color_hi_m = 0.0;  ///< Heights below/above take the end colours.
  double data_lo_m = 0.0, data_hi_m = 0.0;
  /// Data beyond an end of the colour range by more than the note's 1 cm resolution.
  bool clipped() const { return data_lo_m < color_lo_m - 0.005 || data_hi_m > color_hi_m + 0.005; }
  /// The note under the plot's title, e.g. "colours clipped to the 1st..99th height percentile:
  /// -1.20..4.80 m; data -1.50..6.10 m" or "colours span the data: 0.00..3.00 m".
  std::string Describe() const;
};

/// The colour range PlotMapHeight uses for `map` (InvalidArgument without a finite point).
StatusOr<HeightColorRange> MapHeightColorRange(const PointCloud& map);

/// Plot 3. `overlay` (may be empty) is drawn on top as a thin black line.
Status PlotMapHeight(const PointCloud& map, const std::vector<Eigen::Vector3d>& overlay,
                     const std::filesystem::path& png_file,
                     const PlotOptions& options = PlotOptions());

/// One method's GNSS status for plot 4, times relative to the reference [s].
struct GnssStatusTrack {
  struct Span {
    double start_s = 0.0;
    double end_s = 0.0;
    GnssAvailability status = GnssAvailability::kOutage;
  };
  struct Submap {
    int32_t id = 0;
    double start_s = 0.0;  ///< Its first scan.
    double end_s = 0.0;    ///< Its last scan (the next submap's first scan where there is one).
  };
  std::string name;
  std::vector<Span> spans;  ///< Empty: the method used no GNSS (drawn as such).
  std::vector<Submap> submaps;
};

/// A scan's stamp and the submap it went into (LocalizationResult::stamp, ::submap_id).
struct ScanSubmap {
  Timestamp stamp;
  int32_t submap_id = 0;
};

/// Builds a track from a run's availability intervals (MappingSystem::GnssAvailability) and its
/// scans in time order (a submap spans its scans; a new id starts a new submap); times relative
/// to `reference`.
GnssStatusTrack MakeGnssStatusTrack(const std::string& name,
                                    const std::vector<GnssAvailabilityInterval>& availability,
                                    const std::vector<ScanSubmap>& scans, Timestamp reference);

/// The worst status (outage > degraded > available) of `track` over [start_s, end_s); kValid
/// where no span overlaps it.
GnssAvailability WorstGnssStatus(const GnssStatusTrack& track, double start_s, double end_s);

/// Plot 4. `outages`: the requested outage windows (same time base), outlined when present.
Status PlotGnssStatus(const std::vector<GnssStatusTrack>& tracks,
                      const std::vector<OutageWindow>& outages,
                      const std::filesystem::path& png_file,
                      const PlotOptions& options = PlotOptions());

}  // namespace slam_mms::eval
