#pragma once
// Level 2's options and statistics (paper §5.2), as the SDK exposes them:
// MappingSystem::Options::level2 (config keys "level2.*") and MappingSystem::level2_stats(). Level
// 2 itself (the submap manager on the backend's SubmapGraph) is internal (src/pipeline); its
// threads are MappingSystem::Options::num_threads.
//
// Thread safety: plain values.

#include "slam_mms/core/status.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/registration/registration_options.hpp"

namespace slam_mms {

struct Level2Options {
  bool enabled = true;
  bool use_map_to_map = true;
  bool use_gnss = true;
  bool use_loops = true;
  double loop_distance_m = 25.0;  ///< D_thr [m].
  int loop_min_submap_gap = 6;    ///< Candidates at least this many submaps back.
  double loop_min_inlier_ratio = 0.5;
  double loop_max_rms_m = 0.25;
  /// Agreement of a loop with the graph: its correction c of the graph's current relative pose
  /// must have c^T (S_loop + S_chain)^-1 c below this, S_chain being the covariance of the
  /// sequential chain (reckon and map-to-map factors) between the two submaps (a chi-square
  /// with 6 DoF: 22.46 is its 99.9 % quantile). Loose by default: level 1's drift can exceed the
  /// reckon covariance (reckon_sigma_*), and the gate is there for wrong registrations (metres
  /// off), not for drift. > 0.
  double loop_gate_chi2 = 50.0;
  double long_outage_s = 10.0;  ///< GNSS back after at least this long: solve.
  /// F_Reckon's covariance: per axis, a floor plus a rate per metre (the default), or
  /// (reckon_from_level1) level 1's own covariance of the new reference's pose in the previous
  /// submap (SubmapRecord::cov_prev_this: the sliding window's marginal, whose reference is
  /// held), which against the truth on 30 simulated drives is about 1.3x too tight in sigma
  /// (docs/sweep.md, session 38): off by default, an option to measure with. The defaults are
  /// fitted to level 1's reckon errors against the truth of 91 factors of the whole sweep
  /// (session 39; chi2 mean 5.9 / 5.4 / 7.7 of 6 at 0-20 / 20-60 / 60-300 m); the fixed 0.002 rad
  /// / 0.05 m before session 42 were about 3x too loose.
  double reckon_sigma_rot_rad = 0.0003;
  double reckon_sigma_trans_m = 0.01;
  /// Level 1's drift grows with the distance between the two references (d, the reckon's
  /// translation): the sigmas above are the floor, and these add in quadrature per metre of d
  /// (sigma = hypot(floor, per_m * d)) [rad/m] and [m/m]. 0: fixed sigmas. >= 0.
  double reckon_sigma_rot_rad_per_m = 1.0e-5;
  double reckon_sigma_trans_per_m = 3.5e-4;
  bool reckon_from_level1 = false;
  double gnss_sigma_scale = 1.0;  ///< Multiplies the GNSS measurement covariance.
  /// GNSS errors are time-correlated (an RTK-float or single-point bias wanders over tens of
  /// seconds), so fixes at 10 Hz are not independent: the fixes within this window [s] count as
  /// one, i.e. each fix's covariance is multiplied by window / (time since the previous fix),
  /// at least 1. 0 treats every fix as independent. >= 0. On the default drive with a 60 s
  /// outage, 10 s brings the largest error in the outage from 0.81 to 0.45 m (docs/results.md).
  double gnss_correlation_s = 10.0;
  /// With GNSS: an attitude prior on each submap reference. Where the POS attitude is given
  /// (OnSubmapFinished's `pos_attitude`), the prior is the POS's roll, pitch and yaw with the
  /// POS's own covariance: a weaker prior let the GNSS noise rotate the submaps where the
  /// motion holds no rotation information (standing, stop-and-go: 0.19 deg of pitch error
  /// against the POS's 0.01 on a sweep drive; a free yaw turned standing drives by 2-13 deg,
  /// docs/sweep.md). Else level 1's roll and pitch with this sigma [rad] and a free yaw. 0
  /// disables the prior.
  double attitude_prior_sigma_rad = 0.0175;
  /// A POS's attitude error is time-correlated (an initial heading error persists until motion
  /// observes it), so the POS attitude priors of the submaps within this window [s] count as
  /// one: each prior's covariance is multiplied by window / (time since the previous submap's
  /// prior), at least 1, as the GNSS fixes' (gnss_correlation_s). 0 takes every submap's POS
  /// attitude as independent. >= 0.
  double pos_attitude_correlation_s = 0.0;
  /// Chain the POS attitudes of successive submaps with the POS filter's own cross-covariance of
  /// their errors (InsFilter::AttitudeSinceEpoch: every transition and update between the two,
  /// each axis with its own correlation): the first submap's POS attitude a prior, each later
  /// one an attitude chain factor, the conditional of its error given the previous one's
  /// (SubmapGraph::AddAttitudeChainFactor). Where the POS gives no cross-covariance (an external
  /// POS, the first submap after an initialisation or an outage) a prior as above. On by default
  /// since session 42 (docs/sweep.md, "Session 42").
  bool pos_attitude_cross_covariance = true;
  /// GNSS errors as level 2's own Gauss-Markov biases (the POS filter's model, InsFilter::
  /// Options::gnss_error_*) instead of the gnss_correlation_s window: the fixes of one run of a
  /// solution class (RTK fixed, float, code; a new run after another class or a gap of more than
  /// 1.5 s) share a world offset b with the stationary covariance correlated_fraction x the fix's
  /// covariance, a bias node every gnss_bias_node_interval_s, each node following the previous
  /// one with exp(-dt / correlation_time_s) (SubmapGraph::AddGnssBiasLink); the rest of each
  /// fix's covariance is white. A class with correlated_fraction 0 is white (no bias).
  bool gnss_bias_states = false;
  GnssErrorModel gnss_bias_rtk_fixed{0.9, 30.0};
  GnssErrorModel gnss_bias_rtk_float{0.9, 30.0};
  GnssErrorModel gnss_bias_code{0.9, 60.0};
  double gnss_bias_node_interval_s = 1.0;  ///< A new bias node at most this often [s], > 0.
  int max_iterations = 100;  ///< Levenberg-Marquardt iterations of a level-2 solve, > 0.
  /// Map-to-map registration and loop verification.
  PointIcpOptions icp;
  /// InvalidArgument naming "SubmapManager::Options::<field>".
  [[nodiscard]] Status Validate() const;
};

/// What level 2 did so far.
struct Level2Stats {
  int solves = 0;
  int loops_tested = 0;
  int loops_accepted = 0;
  int map_to_map_accepted = 0;
  int gnss_factors = 0;
  double last_solve_ms = 0.0;
};

}  // namespace slam_mms
