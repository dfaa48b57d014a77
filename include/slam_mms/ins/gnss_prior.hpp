#pragma once
// GnssPrior: turns WGS-84 GNSS fixes into position measurements of the antenna in the local ENU
// `world` frame, decides per fix whether to use, down-weight or reject it, tracks the GNSS
// availability over time, injects outages for experiments, and produces the GNSS position factors
// (paper eq 24) for the level-2 graph.
//
// - World frame: GeographicLib::LocalCartesian (exact WGS-84 ENU) anchored at the first valid fix
//   (or an origin set explicitly); the origin is kept so outputs can be geo-referenced.
// - Decision per fix, in this order: withheld (inside an injected outage window) -> reject
//   (fix type below min_fix_type, non-finite values, reported sigma above max_sigma_horizontal_m)
//   -> innovation test against the current estimate when one is given (chi-square of the
//   innovation with the predicted plus measured covariance: above innovation_reject_chi2 rejected,
//   above innovation_downweight_chi2 down-weighted by chi2 / innovation_downweight_chi2; a jump of
//   10-100 m is rejected whenever the estimate is better than a few metres) or, without an
//   estimate, a speed test against the last used fix -> down-weight for a fix type below
//   full_weight_fix_type (variance times downweight_variance_factor) -> use.
//   Sigmas are floored (sigma_floor_*). After max_rejection_streak_s of continuous innovation
//   rejections the next plausible fix is accepted (re-acquisition after a diverged estimate; a
//   multipath episode longer than that is accepted, which is the documented trade-off).
// - Availability at time t: kOutage when no fix was used within outage_timeout_s before t,
//   kDegraded when the last used fix was down-weighted, kValid otherwise.
//
// Ownership: owns its GeographicLib projection (pimpl); move-only.
// Thread safety: not thread-safe for mutation; const queries may run concurrently.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "slam_mms/core/geodesy.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms {

/// Time-correlated GNSS error of one solution type: the share of a fix's variance that is a
/// Gauss-Markov bias and its correlation time (the POS filter's b_gnss, InsFilter::Options; level
/// 2's GNSS bias nodes, Level2Options).
struct GnssErrorModel {
  double correlated_fraction = 0.0;  ///< In [0, 1); 0: white noise.
  double correlation_time_s = 30.0;  ///< > 0 [s].
};

/// The solution class whose error model a fix of this type follows: 0 RTK fixed, 1 RTK float,
/// 2 code (single-point and differential).
inline int GnssSolutionClass(GnssFixType type) {
  return type >= GnssFixType::kRtkFixed ? 0 : type == GnssFixType::kRtkFloat ? 1 : 2;
}

/// A GNSS fix converted to the world frame: position of the antenna with its covariance.
struct GnssMeasurement {
  Timestamp stamp;
  Eigen::Vector3d p_world_antenna = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov_world_antenna =
      Eigen::Matrix3d::Identity();  ///< [m^2], after floors/weights.
  GnssFixType type = GnssFixType::kNone;
};

/// The current estimate of the antenna position, for the innovation test.
struct GnssPrediction {
  Eigen::Vector3d p_world_antenna = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov_world_antenna = Eigen::Matrix3d::Zero();  ///< [m^2]
};

enum class GnssDecision { kUse = 0, kDownWeight = 1, kReject = 2, kWithheld = 3 };
enum class GnssAvailability { kValid = 0, kDegraded = 1, kOutage = 2 };

const char* GnssDecisionName(GnssDecision decision);
const char* GnssAvailabilityName(GnssAvailability availability);

struct GnssDecisionResult {
  GnssDecision decision = GnssDecision::kReject;
  GnssMeasurement measurement;    ///< Valid for kUse and kDownWeight (covariance inflated).
  double innovation_chi2 = -1.0;  ///< Mahalanobis^2 of the innovation; -1 if not tested.
  /// The innovation test's variance factor in the measurement covariance (1 if not inflated);
  /// the rest of the weight is the fix type's.
  double innovation_weight = 1.0;
  Eigen::Vector3d innovation_m = Eigen::Vector3d::Zero();  ///< measured - predicted antenna.
  std::string reason;  ///< Why it was rejected / down-weighted ("" when used).

  bool usable() const {
    return decision == GnssDecision::kUse || decision == GnssDecision::kDownWeight;
  }
};

/// A maximal interval of constant availability, [start, end).
struct GnssAvailabilityInterval {
  Timestamp start;
  Timestamp end;
  GnssAvailability availability = GnssAvailability::kOutage;
};

class GnssPrior {
 public:
  struct Options {
    Eigen::Vector3d t_body_antenna = Eigen::Vector3d::Zero();  ///< Lever arm in body [m].
    double sigma_floor_horizontal_m = 0.02;  ///< Reported horizontal sigma floored to this [m].
    double sigma_floor_vertical_m = 0.03;    ///< Reported vertical sigma floored to this [m].
    double max_sigma_horizontal_m = 10.0;    ///< Fixes reporting more are rejected [m].
    GnssFixType min_fix_type = GnssFixType::kSingle;            ///< Below: rejected.
    GnssFixType full_weight_fix_type = GnssFixType::kRtkFloat;  ///< Below: down-weighted.
    double downweight_variance_factor = 4.0;    ///< Variance factor of a down-weighted type (>= 1).
    double innovation_downweight_chi2 = 11.34;  ///< 3 dof, 99 %: above it, down-weight.
    double innovation_reject_chi2 = 16.27;      ///< 3 dof, 99.9 %: above it, reject.
    double max_rejection_streak_s =
        10.0;                       ///< Continuous innovation rejections before re-acquiring [s].
    double max_speed_mps = 70.0;    ///< Speed test between fixes when no estimate is given.
    double outage_timeout_s = 1.5;  ///< No used fix for this long: outage [s].

    [[nodiscard]] Status Validate() const;
  };

  /// Default options.
  GnssPrior();
  /// Validates the options.
  static StatusOr<GnssPrior> Create(const Options& options);
  ~GnssPrior();
  GnssPrior(GnssPrior&&) noexcept;
  GnssPrior& operator=(GnssPrior&&) noexcept;
  GnssPrior(const GnssPrior&) = delete;
  GnssPrior& operator=(const GnssPrior&) = delete;

  // ---- world frame ---------------------------------------------------------------------------
  /// Anchors the world frame explicitly (otherwise the first valid fix does). Fails if already set.
  [[nodiscard]] Status SetOrigin(const GeodeticPoint& origin);
  bool has_origin() const;
  /// The WGS-84 origin of `world` (zeros until set).
  GeodeticPoint origin() const;
  /// WGS-84 -> world ENU [m]; FailedPrecondition without origin.
  StatusOr<Eigen::Vector3d> ToWorld(const GeodeticPoint& point) const;
  /// world ENU -> WGS-84.
  StatusOr<GeodeticPoint> ToGeodetic(const Eigen::Vector3d& p_world) const;

  // ---- outage injection ----------------------------------------------------------------------
  /// Reference time of the outage windows (the first scan). If never set, the first fix's stamp.
  void SetReferenceTime(Timestamp t0);
  /// Fixes in [t0 + start_s, t0 + start_s + duration_s) are withheld.
  [[nodiscard]] Status AddOutageWindow(double start_s, double duration_s);
  bool IsWithheld(Timestamp t) const;

  // ---- per-fix decision ----------------------------------------------------------------------
  /// Converts a fix (floors, lever arm untouched: this is the antenna) without deciding or
  /// recording anything. Anchors the origin on the first valid fix.
  StatusOr<GnssMeasurement> ToMeasurement(const GnssFix& fix);
  /// Decides on one fix (see the class comment) and records the decision for availability.
  /// `prediction` may be null (no estimate yet). Fixes must come in time order.
  StatusOr<GnssDecisionResult> Process(const GnssFix& fix, const GnssPrediction* prediction);

  // ---- availability --------------------------------------------------------------------------
  GnssAvailability AvailabilityAt(Timestamp t) const;
  /// The availability history from the first processed fix to the last one + outage_timeout_s.
  std::vector<GnssAvailabilityInterval> AvailabilityIntervals() const;
  int num_used() const;
  int num_downweighted() const;
  int num_rejected() const;
  int num_withheld() const;

  const Options& options() const;

 private:
  explicit GnssPrior(const Options& options);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
