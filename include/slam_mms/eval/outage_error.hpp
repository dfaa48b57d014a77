#pragma once
// Errors inside GNSS-outage windows (paper Table 2, Figs. 13-15): for each window
// [start, start + duration) the maximum and RMS position and rotation errors of the poses whose
// stamps fall inside it, and the same over all windows together.
//
// Window times are seconds relative to a reference time the caller gives (slam_mms_run: the drive's
// first scan), as in report.json's "gnss_outages": [[start_s, duration_s], ...].
//
// Thread safety: free functions on value types; safe to call concurrently.

#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/eval/trajectory_error.hpp"

namespace slam_mms::eval {

struct OutageWindow {
  double start_s = 0.0;     ///< Start relative to the reference time [s].
  double duration_s = 0.0;  ///< Length [s]; the window is [start_s, start_s + duration_s).

  /// True when `t` lies inside [start, start + duration) relative to `reference`.
  bool Contains(Timestamp t, Timestamp reference) const;
};

struct WindowError {
  OutageWindow window;
  size_t num_poses = 0;  ///< Matched poses inside the window; the errors below are 0 when none.
  double max_pos_err_m = 0.0;
  double rms_pos_err_m = 0.0;
  double max_rot_err_deg = 0.0;
  double rms_rot_err_deg = 0.0;
};

struct OutageErrorResult {
  std::vector<WindowError> windows;  ///< One per input window, in input order.
  /// Over all windows together (a pose inside two overlapping windows counts once).
  size_t num_poses = 0;
  double max_pos_err_m = 0.0;
  double rms_pos_err_m = 0.0;
  double max_rot_err_deg = 0.0;
  double rms_rot_err_deg = 0.0;
};

/// Validates the windows (finite start, duration > 0) and evaluates `errors` (from ComputeAte)
/// inside them. An empty window list gives an empty result with num_poses = 0.
StatusOr<OutageErrorResult> ComputeOutageErrors(const std::vector<PoseError>& errors,
                                                const std::vector<OutageWindow>& windows,
                                                Timestamp reference);

}  // namespace slam_mms::eval
