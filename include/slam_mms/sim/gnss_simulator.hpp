#pragma once
// GnssSimulator: the error process of the POS position (what an RT3003-class GNSS/INS reports),
// stepped at a fixed rate (100 Hz) along the drive.
//
// A state machine over RTK fixed / RTK float / single point (SPS) / none:
// - urban-canyon degradation: the sky blockage above the antenna (ray cast into the scene) sets the
//   best state reachable (open sky: fixed; partial: float; deep canyon: SPS; covered: none);
//   a worse target is followed within about a second, a better one only after a re-acquisition /
//   RTK convergence delay drawn per transition (SPS 1-3 s, float 5-15 s, fixed 10-30 s);
// - scripted outages (start, duration relative to the first scan) force "none";
// - errors per state: a first-order Gauss-Markov bias (fixed: 1.5 cm h / 2.5 cm v, tau 30 s;
//   float: 0.25 / 0.4 m, tau 20 s; SPS: 1.5 / 2.5 m, tau 60 s) plus white noise of a fifth of that
//   at each 10 Hz epoch; SPS also has multipath jumps (Poisson, rate grows with blockage, size
//   N(0, 3 m) horizontal, decaying with tau 5-20 s);
// - "none": the INS dead-reckons: the error continues from where it was with a velocity and
//   acceleration drift, and converges back to the GNSS error (tau 2 s) when fixes return;
// - the reported sigma is the state's nominal sigma times a slowly varying factor exp(N(0,
// 0.25^2)),
//   close to but not equal to the true error statistics; during "none" it grows with time.
//
// Thread safety: none (stateful).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"

namespace slam_mms::sim {

enum class GnssState { kNone = 0, kSps = 1, kRtkFloat = 2, kRtkFixed = 3 };
const char* GnssStateName(GnssState s);

struct GnssOutage {
  double start_s = 0.0;  ///< Seconds after the first scan's start.
  double duration_s = 0.0;
};

/// One step of the error process.
struct GnssSample {
  GnssState state = GnssState::kRtkFixed;
  Eigen::Vector3d error_enu_m = Eigen::Vector3d::Zero();  ///< Reported minus true position.
  double sigma_horizontal_m = 0.02;  ///< Reported 1-sigma (per axis, north/east).
  double sigma_vertical_m = 0.03;
  int num_satellites = 10;
  double sky_blockage = 0.0;
  bool in_scripted_outage = false;
};

class GnssSimulator {
 public:
  struct Options {
    double rate_hz = 100.0;
    double epoch_rate_hz = 10.0;  ///< White noise is redrawn at this rate (receiver epochs).
    GnssState best_state = GnssState::kRtkFixed;  ///< Best quality reachable ("GNSS quality").
    double sigma_fixed_h_m = 0.015, sigma_fixed_v_m = 0.025;
    double sigma_float_h_m = 0.25, sigma_float_v_m = 0.4;
    double sigma_sps_h_m = 1.5, sigma_sps_v_m = 2.5;
    double multipath_rate_hz = 0.01;  ///< SPS jump rate in open sky (x (1 + 10 blockage)).
    double multipath_sigma_m = 3.0;
    double urban_canyon_scale = 1.0;  ///< Multiplies the sky blockage; 0 disables degradation.
    /// Blockage thresholds: above each the best state drops to float / SPS / none.
    double blockage_float = 0.35, blockage_sps = 0.5, blockage_none = 0.75;
    double ins_velocity_drift_sigma_mps = 0.02;  ///< During "none".
    double ins_accel_drift_sigma_mps2 = 0.001;
    std::vector<GnssOutage> outages;

    [[nodiscard]] Status Validate() const;
  };

  GnssSimulator(const Options& options, uint64_t seed);

  /// Advances one step (1 / rate_hz) to `t_since_first_scan_s`; `sky_blockage` in [0, 1].
  GnssSample Step(double t_since_first_scan_s, double sky_blockage);

  /// Whether `t` lies in a scripted outage.
  bool InOutage(double t_since_first_scan_s) const;
  const Options& options() const { return options_; }

 private:
  double Normal();
  double Uniform();
  void Enter(GnssState s, double t);
  Eigen::Vector3d Sigma(GnssState s) const;

  Options options_;
  uint64_t rng_;
  bool has_spare_ = false;
  double spare_ = 0.0;
  GnssState state_;
  double t_state_ = 0.0, upgrade_delay_ = 0.0, t_prev_ = -1e9, next_epoch_ = -1e9;
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero(), white_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d jump_ = Eigen::Vector3d::Zero();
  double jump_tau_ = 10.0;
  Eigen::Vector3d error_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d drift_v_ = Eigen::Vector3d::Zero(), drift_a_ = Eigen::Vector3d::Zero();
  double t_outage_start_ = 0.0, sigma_at_outage_ = 0.0;
  double sigma_factor_log_ = 0.0;
  int sats_ = 10;
};

}  // namespace slam_mms::sim
