#pragma once
// An OXTS (GNSS/INS) record stream as a reference trajectory, and how far its position track
// agrees with its own velocities over short windows.
//
// A real drive's reference is the RT3003's own solution. Its positions follow the GNSS (on
// KITTI mostly differential or RTK float, 0.1-0.4 m), so over a second they wander: on the 50
// real frames of drive 0013 the position track runs about 1 deg off the direction of the
// recorded velocity, and across KITTI's drives the position increments over 1 s disagree with
// the integrated velocities by about 1 % of the distance (docs/simulator.md, "The real
// reference"). Relative errors over 10-50 m against such a reference measure the reference as
// much as the odometry. Its velocities (from the IMU, GNSS Doppler-aided) are far smoother, so
// the first record's position carried along by the integrated velocities is the sharper
// reference over short segments; it drifts with the velocity error (a few cm/s) and is not an
// absolute one (use the recorded positions for ATE and for segments of minutes).
//
// Errors: kInvalidArgument for fewer than 2 records; kDataLoss naming the record for stamps that
// do not increase, a gap over `max_gap_s`, or a non-finite field. Thread safety: free functions.

#include <cstddef>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"

namespace slam_mms::eval {

enum class OxtsPositions {
  kRecorded,            ///< lat/lon/alt of each record.
  kVelocityIntegrated,  ///< The first record's position + the trapezoidal integral of vn/ve/vu.
};

struct OxtsTrajectoryOptions {
  OxtsPositions positions = OxtsPositions::kRecorded;
  /// The largest step between two records the velocity integral bridges [s].
  double max_gap_s = 0.5;
};

/// The records as T_world_body in the run's local ENU frame about `run_origin` (attitudes as
/// recorded: relative to the local level frame at each record, rotated into the run frame).
StatusOr<Trajectory> OxtsTrajectory(const std::vector<StampedOxts>& records,
                                    const GeodeticPoint& run_origin,
                                    const OxtsTrajectoryOptions& options = OxtsTrajectoryOptions());

/// How the position increments of `track` over windows of `window_s` agree with those of
/// `reference` at the same stamps (e.g. an OXTS's recorded positions against its integrated
/// velocities): the difference (track - reference) in the horizontal plane, split along and
/// across the reference's increment, in % of the reference's horizontal distance; vertical
/// in % too. Windows start at every pose of `track` and end at its first pose at least
/// `window_s` later; windows shorter than `min_distance_m` (standing, crawling) are skipped.
struct IncrementAgreement {
  double window_s = 0.0;
  size_t windows = 0;
  double mean_distance_m = 0.0;
  double rms_pct = 0.0;  ///< RMS of the horizontal difference.
  double along_mean_pct = 0.0, along_std_pct = 0.0;
  double cross_mean_pct = 0.0, cross_std_pct = 0.0;  ///< + = to the left of the motion.
  double vertical_rms_pct = 0.0;
};

StatusOr<IncrementAgreement> CompareIncrements(const Trajectory& track, const Trajectory& reference,
                                               double window_s = 1.0, double min_distance_m = 5.0);

}  // namespace slam_mms::eval
