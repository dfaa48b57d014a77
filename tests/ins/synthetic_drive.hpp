#pragma once
// An analytic drive for the ins tests: smooth position with turns, small roll/pitch oscillations,
// and the exact velocity, acceleration, attitude, body angular rate and specific force, so a
// perfect IMU and perfect GNSS can be generated at any time. World = ENU, body x forward, z up.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/sensor_data.hpp"

namespace slam_mms::testing {

struct TruthState {
  Eigen::Vector3d p, v, a;  // world
  Eigen::Matrix3d R;        // R_world_body
  Eigen::Vector3d w_body;   // angular rate in body
  Eigen::Vector3d f_body;   // specific force in body
};

class SyntheticDrive {
 public:
  explicit SyntheticDrive(double gravity_mps2 = 9.80665) : g_(gravity_mps2) {}

  double gravity() const { return g_; }

  TruthState At(double t) const {
    TruthState s;
    // Position: forward 10 m/s with a slow S-curve (headings swing about +-35 deg) and a hill.
    s.p = {kV0 * t + kA1 * std::sin(kW1 * t),
           kB1 * (1.0 - std::cos(kW1 * t)) + kB2 * std::sin(kW2 * t), kC * std::sin(kW3 * t)};
    s.v = {kV0 + kA1 * kW1 * std::cos(kW1 * t),
           kB1 * kW1 * std::sin(kW1 * t) + kB2 * kW2 * std::cos(kW2 * t),
           kC * kW3 * std::cos(kW3 * t)};
    s.a = {-kA1 * kW1 * kW1 * std::sin(kW1 * t),
           kB1 * kW1 * kW1 * std::cos(kW1 * t) - kB2 * kW2 * kW2 * std::sin(kW2 * t),
           -kC * kW3 * kW3 * std::sin(kW3 * t)};
    const double yaw = std::atan2(s.v.y(), s.v.x());
    const double yaw_rate =
        (s.v.x() * s.a.y() - s.v.y() * s.a.x()) / (s.v.x() * s.v.x() + s.v.y() * s.v.y());
    const double roll = kRoll * std::sin(kWr * t);
    const double roll_rate = kRoll * kWr * std::cos(kWr * t);
    const double pitch = kPitch * std::sin(kWp * t + 1.0);
    const double pitch_rate = kPitch * kWp * std::cos(kWp * t + 1.0);
    s.R = FromRollPitchYaw(roll, pitch, yaw);  // Rz(yaw) Ry(pitch) Rx(roll)
    // Body rates of the ZYX Euler sequence.
    s.w_body = {roll_rate - yaw_rate * std::sin(pitch),
                pitch_rate * std::cos(roll) + yaw_rate * std::sin(roll) * std::cos(pitch),
                -pitch_rate * std::sin(roll) + yaw_rate * std::cos(roll) * std::cos(pitch)};
    s.f_body = s.R.transpose() * (s.a - Eigen::Vector3d(0.0, 0.0, -g_));
    return s;
  }

  ImuSample PerfectImu(double t, Timestamp t0) const {
    const TruthState s = At(t);
    ImuSample m;
    m.stamp = t0.PlusSeconds(t);
    m.accel_mps2 = s.f_body;
    m.gyro_radps = s.w_body;
    return m;
  }

 private:
  static constexpr double kV0 = 10.0, kA1 = 20.0, kW1 = 0.1, kB1 = 60.0, kB2 = 5.0, kW2 = 0.3;
  static constexpr double kC = 2.0, kW3 = 0.05;
  static constexpr double kRoll = 0.03, kWr = 0.4, kPitch = 0.02, kWp = 0.25;
  double g_;
};

}  // namespace slam_mms::testing
