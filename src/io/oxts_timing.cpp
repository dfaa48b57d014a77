#include "slam_mms/io/oxts_timing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/io/oxts_record.hpp"

namespace slam_mms {

StatusOr<OxtsInertialDelay> EstimateOxtsInertialDelay(const std::vector<StampedOxts>& records,
                                                      const OxtsInertialDelayOptions& options) {
  if (!(options.max_delay_s > 0.0) || !(options.step_s > 0.0) || !(options.min_improvement > 1.0) ||
      options.max_delay_s / options.step_s > 1e4) {
    return InvalidArgumentError(
        "OxtsInertialDelayOptions: max_delay_s and step_s must be > 0 (at most 1e4 steps) and "
        "min_improvement > 1");
  }
  const size_t n = records.size();
  if (n < 3) {
    return FailedPreconditionError("EstimateOxtsInertialDelay: " + std::to_string(n) +
                                   " records; at least 3 are needed");
  }
  std::vector<double> t(n);
  for (size_t i = 0; i < n; ++i) t[i] = records[i].stamp.SecondsSince(records.front().stamp);
  std::vector<double> dt(n - 1);
  for (size_t i = 0; i + 1 < n; ++i) dt[i] = t[i + 1] - t[i];
  std::vector<double> sorted_dt = dt;
  std::nth_element(sorted_dt.begin(), sorted_dt.begin() + sorted_dt.size() / 2, sorted_dt.end());
  const double step = sorted_dt[sorted_dt.size() / 2];
  // The attitude's body rate at record i from its neighbours (records about one step apart).
  struct Rate {
    double t;
    Eigen::Vector3d w;
  };
  std::vector<Rate> attitude_rates;
  for (size_t i = 1; i + 1 < n; ++i) {
    const double span = t[i + 1] - t[i - 1];
    if (!(span > 1.5 * step && span < 2.5 * step)) continue;
    const Eigen::Matrix3d R0 = OxtsAttitude(records[i - 1].record);
    const Eigen::Matrix3d R1 = OxtsAttitude(records[i + 1].record);
    const Eigen::Vector3d w = so3::Log(R0.transpose() * R1) / span;
    if (w.allFinite()) attitude_rates.push_back({t[i], w});
  }
  auto recorded = [&](size_t k) {
    const OxtsRecord& r = records[k].record;
    return Eigen::Vector3d(r.wx, r.wy, r.wz);
  };
  // RMS of recorded(t + delay) - attitude rate(t), the recorded rates linearly interpolated.
  auto rms = [&](double delay, size_t* count) {
    double sum = 0.0;
    size_t m = 0, k = 0;
    for (const Rate& a : attitude_rates) {
      const double tq = a.t + delay;
      if (tq < t.front() || tq > t.back()) continue;
      while (k + 1 < n && t[k + 1] < tq) ++k;
      while (k > 0 && t[k] > tq) --k;
      if (k + 1 >= n) continue;
      const double span = t[k + 1] - t[k];
      if (!(span > 0.0) || span > 1.5 * step) continue;  // no record gap bridged
      const double u = (tq - t[k]) / span;
      const Eigen::Vector3d w = (1.0 - u) * recorded(k) + u * recorded(k + 1);
      if (!w.allFinite()) continue;
      sum += (w - a.w).squaredNorm();
      ++m;
    }
    if (count != nullptr) *count = m;
    return m > 0 ? std::sqrt(sum / static_cast<double>(m))
                 : std::numeric_limits<double>::infinity();
  };
  OxtsInertialDelay out;
  out.rms_at_zero_radps = rms(0.0, &out.samples);
  out.rms_at_delay_radps = out.rms_at_zero_radps;
  const int steps = static_cast<int>(std::floor(options.max_delay_s / options.step_s + 1e-9));
  for (int j = -steps; j <= steps; ++j) {
    const double delay = j * options.step_s;
    const double r = rms(delay, nullptr);
    if (r < out.rms_at_delay_radps) {
      out.rms_at_delay_radps = r;
      out.delay_s = delay;
    }
  }
  // A fit that only a delay makes: nothing moving (both RMS 0) or no better fit is not clear.
  out.clear = out.samples >= options.min_samples && std::isfinite(out.rms_at_zero_radps) &&
              out.rms_at_zero_radps > 0.0 && out.delay_s != 0.0 &&
              out.rms_at_delay_radps * options.min_improvement <= out.rms_at_zero_radps;
  return out;
}

}  // namespace slam_mms
