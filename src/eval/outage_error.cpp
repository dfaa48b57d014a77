#include "slam_mms/eval/outage_error.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace slam_mms::eval {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

struct Accumulator {
  size_t n = 0;
  double max_pos = 0.0, sq_pos = 0.0, max_rot = 0.0, sq_rot = 0.0;

  void Add(const PoseError& e) {
    ++n;
    max_pos = std::max(max_pos, e.position_error_m);
    sq_pos += e.position_error_m * e.position_error_m;
    const double rot_deg = e.rotation_error_rad * kRadToDeg;
    max_rot = std::max(max_rot, rot_deg);
    sq_rot += rot_deg * rot_deg;
  }
  double RmsPos() const { return n == 0 ? 0.0 : std::sqrt(sq_pos / static_cast<double>(n)); }
  double RmsRot() const { return n == 0 ? 0.0 : std::sqrt(sq_rot / static_cast<double>(n)); }
};

}  // namespace

bool OutageWindow::Contains(Timestamp t, Timestamp reference) const {
  const double s = t.SecondsSince(reference);
  return s >= start_s && s < start_s + duration_s;
}

StatusOr<OutageErrorResult> ComputeOutageErrors(const std::vector<PoseError>& errors,
                                                const std::vector<OutageWindow>& windows,
                                                Timestamp reference) {
  for (size_t w = 0; w < windows.size(); ++w) {
    if (!std::isfinite(windows[w].start_s) || !(windows[w].duration_s > 0.0) ||
        !std::isfinite(windows[w].duration_s)) {
      return InvalidArgumentError("ComputeOutageErrors: window " + std::to_string(w) + " = [" +
                                  std::to_string(windows[w].start_s) + " s, +" +
                                  std::to_string(windows[w].duration_s) +
                                  " s); start must be finite and duration finite and > 0");
    }
  }
  OutageErrorResult result;
  std::vector<Accumulator> per_window(windows.size());
  Accumulator all;
  for (const PoseError& e : errors) {
    bool inside_any = false;
    for (size_t w = 0; w < windows.size(); ++w) {
      if (windows[w].Contains(e.stamp, reference)) {
        per_window[w].Add(e);
        inside_any = true;
      }
    }
    if (inside_any) all.Add(e);
  }
  for (size_t w = 0; w < windows.size(); ++w) {
    WindowError we;
    we.window = windows[w];
    we.num_poses = per_window[w].n;
    we.max_pos_err_m = per_window[w].max_pos;
    we.rms_pos_err_m = per_window[w].RmsPos();
    we.max_rot_err_deg = per_window[w].max_rot;
    we.rms_rot_err_deg = per_window[w].RmsRot();
    result.windows.push_back(we);
  }
  result.num_poses = all.n;
  result.max_pos_err_m = all.max_pos;
  result.rms_pos_err_m = all.RmsPos();
  result.max_rot_err_deg = all.max_rot;
  result.rms_rot_err_deg = all.RmsRot();
  return result;
}

}  // namespace slam_mms::eval
