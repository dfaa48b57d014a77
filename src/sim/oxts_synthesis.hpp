#pragma once
// OXTS record synthesis (private): the 30 fields from the true state, the IMU measurement, the GNSS
// error process and an INS attitude/velocity error process.
#include <GeographicLib/LocalCartesian.hpp>

#include "slam_mms/io/oxts_record.hpp"
#include "slam_mms/sim/gnss_simulator.hpp"
#include "slam_mms/sim/reference_trajectory.hpp"

namespace slam_mms::sim {

class InsErrorProcess {
 public:
  InsErrorProcess(double roll_pitch_sigma, double yaw_sigma, double velocity_sigma, uint64_t seed);
  void Step(double dt, bool gnss_available);
  Eigen::Vector3d rpy_error() const { return rpy_; }
  Eigen::Vector3d velocity_error() const { return vel_; }

 private:
  double Normal();
  double rp_sigma_, yaw_sigma_, vel_sigma_;
  uint64_t rng_;
  Eigen::Vector3d rpy_ = Eigen::Vector3d::Zero(), vel_ = Eigen::Vector3d::Zero();
};

int PosMode(GnssState s);

/// A record at `truth`'s time: positions and attitude from `truth`, velocities from
/// `inertial_truth` (the same state, or an earlier one for KITTI-like lagging inertial outputs),
/// accelerations and rates from `imu` (measured at `inertial_truth`).
OxtsRecord SynthesizeOxts(const BodyState& truth, const BodyState& inertial_truth,
                          const ImuSample& imu, const GnssSample& gnss, const InsErrorProcess& ins,
                          const GeographicLib::LocalCartesian& enu);

}  // namespace slam_mms::sim
