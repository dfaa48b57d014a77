#pragma once
// PNG plots of the evaluation report, drawn with OpenCV (no plotting library):
//   1. PlotTrajectoriesTopView: the ground truth and several methods seen from above (x east, y
//      north, equal scale, metre axes), the parts inside GNSS-outage windows drawn thicker over an
//      orange band, start marked, legend.
//   2. PlotPositionErrors: position error over time per method, outage windows shaded.
//   3. PlotMapHeight: a map seen from above, each pixel coloured by the height of its highest point
//      (turbo colour map, clipped to the 1st..99th height percentile), with a colour bar, metre
//      axes and an optional trajectory overlay.
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

namespace slam_mms::eval {

struct PlotOptions {
  int width_px = 1400;
  int height_px = 1050;
  std::string title;  ///< Empty: a default title per plot.

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
  std::vector<double> error_m;
};

/// Builds an ErrorSeries from per-pose errors (ComputeAte's AteResult::errors).
ErrorSeries MakeErrorSeries(const std::string& name, const std::vector<PoseError>& errors,
                            Timestamp reference);

/// Plot 2. Outage windows are in the same time base as the series.
Status PlotPositionErrors(const std::vector<ErrorSeries>& series,
                          const std::vector<OutageWindow>& outages,
                          const std::filesystem::path& png_file,
                          const PlotOptions& options = PlotOptions());

/// Plot 3. `overlay` (may be empty) is drawn on top as a thin black line.
Status PlotMapHeight(const PointCloud& map, const std::vector<Eigen::Vector3d>& overlay,
                     const std::filesystem::path& png_file,
                     const PlotOptions& options = PlotOptions());

}  // namespace slam_mms::eval
