#pragma once
// PosSmoother: the post-processed POS of a survey workflow (what POSPac-class software calls an
// SBET, a smoothed best estimate of trajectory): the forward error-state EKF (InsFilter) over a
// whole IMU + GNSS stream, then a Rauch-Tung-Striebel backward pass over its recorded steps, the
// smoothed error injected into the nominal states. Method `gnss_ins_smoothed`, and the POS that
// `full` runs on offline (ARCHITECTURE.md, "Two POS workflows"; docs/ins.md).
//
// RTS over the error state (Smooth): with, per step k, the a-priori nominal x_k^- and covariance
// P_k^-, the a-posteriori x_k^+ and P_k^+, and the transition F_k (previous a-posteriori error to
// this a-priori error), from the last step back:
//   C_k      = P_k^+ F_{k+1}^T (P_{k+1}^-)^-1
//   dx_k^s   = C_k (x_{k+1}^s [-] x_{k+1}^-)          (the smoothed error about x_k^+)
//   P_k^s    = P_k^+ + C_k (P_{k+1}^s - P_{k+1}^-) C_k^T
//   x_k^s    = x_k^+ [+] dx_k^s
// with [+]/[-] the filter's own error definition: dp, dv, dba, dbg additive, dtheta right
// (R = R_hat Exp(dtheta)). The filter's errors at x_k^+ have zero mean, so this is the linear RTS
// smoother about the forward trajectory; P_{k+1}^s is used in the tangent of x_{k+1}^- (first
// order). On a linear model it equals the batch least-squares solution (tested).
//
// Thread safety: stateless functions; concurrent calls on distinct inputs are safe.

#include <optional>
#include <utility>
#include <vector>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/ins/ins_filter.hpp"

namespace slam_mms {

class PosSmoother {
 public:
  struct Options {
    /// The forward filter (record_steps is set by Run).
    InsFilter::Options ins;
    /// World origin; empty = the first valid GNSS fix (as MappingSystem).
    std::optional<GeodeticPoint> origin;
    /// GNSS outage windows [start_s, start_s + duration_s) relative to outage_reference.
    std::vector<std::pair<double, double>> gnss_outages;
    /// Reference time of the outage windows (the first scan's start); empty = the first fix.
    std::optional<Timestamp> outage_reference;
    /// The initial attitude's stated 1-sigma roll, pitch, yaw [rad] (InsFilter::
    /// InitializeAttitude); empty: ins.init_sigma_roll_pitch_rad / init_sigma_yaw_rad.
    std::optional<Eigen::Vector3d> initial_sigma_rpy_rad;
    [[nodiscard]] Status Validate() const;
  };

  struct Result {
    std::vector<InsState> forward;   ///< The forward filter's state at every step.
    std::vector<InsState> smoothed;  ///< The smoothed state at every step (same stamps).
    GeodeticPoint origin;            ///< The world origin used.
    std::vector<GnssAvailabilityInterval> availability;  ///< Of the forward pass.
    int gnss_used = 0;  ///< Fixes used (incl. down-weighted) by the forward pass.
  };

  /// Forward filter then RTS over `imu` and `gnss` (each strictly time-ordered; merged, IMU first
  /// at equal stamps). `initial` gives the attitude and velocity at its stamp (InsFilter::
  /// InitializeAttitude; the position comes from the first usable fix); without it the filter
  /// cannot start: FailedPrecondition. InvalidArgument for bad options or unordered streams;
  /// FailedPrecondition when no usable fix started the filter.
  static StatusOr<Result> Run(const Options& options, const std::vector<ImuSample>& imu,
                              const std::vector<GnssFix>& gnss,
                              const std::optional<InsState>& initial);

  /// The backward pass alone over a filter's recorded steps (InsFilter::Steps()): one smoothed
  /// state per step, with the smoothed pose covariance. InvalidArgument if `steps` is empty, not
  /// strictly time-ordered or holds a non-finite or non-positive-definite a-priori covariance.
  static StatusOr<std::vector<InsState>> Smooth(const std::vector<InsFilterStep>& steps);

  /// Same, also returning the smoothed 22x22 error covariances (about the smoothed states).
  static StatusOr<std::vector<InsState>> Smooth(const std::vector<InsFilterStep>& steps,
                                                std::vector<InsErrorMatrix>* P_smoothed);
};

}  // namespace slam_mms
