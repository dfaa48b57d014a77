#pragma once
// The delay of an OXTS record stream's inertial outputs behind its navigation outputs.
//
// In KITTI's raw recordings the OXTS's angular rates, accelerations and velocities describe the
// motion about 50 ms before the record's time, while its positions and attitude (and the LiDAR)
// are on time: across the 56 moving drives of KITTI's OXTS data the recorded rates fit the
// attitude's time derivative best 50-55 ms later, and on drive 0013 the LiDAR odometry's yaw rate
// fits the OXTS attitude at no lag and its recorded yaw rate 50-75 ms later (docs/simulator.md,
// "The real reference"). Fed as they are, they are an IMU 50 ms late: on a simulated drive with
// turns that lag took `full` from 0.14 to 0.92 m ATE and 0.15 to 1.28 deg of rotation error
// (docs/io.md, "KITTI's OXTS timing").
//
// EstimateOxtsInertialDelay finds the delay from the records alone: the body rate the attitudes
// give (central differences, Log(R_{i-1}^T R_{i+1}) / dt) against the recorded body rates
// (wx, wy, wz) read `delay` later, RMS over the records, on a grid. The simulator's records,
// written on time, give 0. Thread safety: a free function.

#include <cstddef>
#include <vector>

#include "slam_mms/core/status.hpp"

namespace slam_mms {

struct StampedOxts;  // slam_mms/io/kitti_raw_reader.hpp

struct OxtsInertialDelayOptions {
  double max_delay_s = 0.15;  ///< The grid spans [-max, max] [s], > 0.
  double step_s = 0.005;      ///< Grid step [s], > 0.
  /// The estimate is `clear` with at least this many rate comparisons ...
  size_t min_samples = 10;
  /// ... and an RMS at the best delay at least this many times smaller than at 0 (> 1).
  double min_improvement = 1.5;
};

struct OxtsInertialDelay {
  double delay_s = 0.0;             ///< The best delay on the grid [s].
  double rms_at_delay_radps = 0.0;  ///< RMS rate difference there [rad/s].
  double rms_at_zero_radps = 0.0;   ///< ... and without a delay.
  size_t samples = 0;               ///< Records compared (at delay 0).
  bool clear = false;               ///< See OxtsInertialDelayOptions; else use 0.
};

/// Records in time order (KittiRawReader's). kInvalidArgument for bad options; kFailedPrecondition
/// with fewer than 3 records.
StatusOr<OxtsInertialDelay> EstimateOxtsInertialDelay(
    const std::vector<StampedOxts>& records,
    const OxtsInertialDelayOptions& options = OxtsInertialDelayOptions());

}  // namespace slam_mms
