#pragma once
// An analytic drive for the ins tests: smooth position with turns, small roll/pitch oscillations,
// and the exact velocity, acceleration, attitude, body angular rate and specific force, so a
// perfect IMU and perfect GNSS can be generated at any time. World = ENU, body x forward, z up.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/ins/ins_filter.hpp"

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

// The drives' start and world origin (the ins tests').
inline const Timestamp kT0 = Timestamp::FromSeconds(1317000000.0);
inline const GeodeticPoint kOrigin{49.011, 8.4165, 112.0};

// An RTK-fixed fix of the antenna at `g` with the given sigmas [m].
inline GnssFix RtkFix(Timestamp stamp, const GeodeticPoint& g, double sigma_horizontal_m,
                      double sigma_vertical_m) {
  GnssFix fix;
  fix.stamp = stamp;
  fix.latitude_deg = g.latitude_deg;
  fix.longitude_deg = g.longitude_deg;
  fix.height_m = g.height_m;
  fix.sigma_horizontal_m = sigma_horizontal_m;
  fix.sigma_vertical_m = sigma_vertical_m;
  fix.type = GnssFixType::kRtkFixed;
  return fix;
}

// A noisy drive along SyntheticDrive from `t0`, world origin `origin`: the IMU with the noise
// and bias random walks of the filter options `o`, RTK fixes of 2 / 3 cm (horizontal / vertical)
// at 10 Hz of the antenna at o.gnss.t_body_antenna, and an initial state drawn around the truth.
struct NoisyDrive {
  std::vector<ImuSample> imu;  // 100 Hz
  std::vector<GnssFix> gnss;   // stamped with every tenth IMU sample
  InsState initial;
};

// The initial errors' sigmas: roll, pitch, yaw [rad] (world axes), position [m] (0: exact, no
// draw), velocity [m/s], accelerometer and gyro biases.
struct NoisyDriveSigmas {
  double roll_pitch_rad = 0.003, yaw_rad = 0.01, position_m = 0.0, velocity_mps = 0.05;
  double accel_bias_mps2 = 0.02, gyro_bias_radps = 2e-4;
};

inline NoisyDrive MakeNoisyDrive(const InsFilter::Options& o, double duration_s, uint32_t seed,
                                 Timestamp t0, const GeodeticPoint& origin,
                                 const NoisyDriveSigmas& sig = NoisyDriveSigmas()) {
  const SyntheticDrive drive;
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto randn3 = [&]() { return Eigen::Vector3d(n01(rng), n01(rng), n01(rng)); };
  GnssPrior geo;
  EXPECT_TRUE(geo.SetOrigin(origin).ok());
  NoisyDrive d;
  const TruthState s0 = drive.At(0.0);
  d.initial.stamp = t0;
  const Eigen::Vector3d dtheta(sig.roll_pitch_rad * n01(rng), sig.roll_pitch_rad * n01(rng),
                               sig.yaw_rad * n01(rng));
  const Eigen::Vector3d dp =
      sig.position_m > 0.0 ? Eigen::Vector3d(sig.position_m * randn3()) : Eigen::Vector3d::Zero();
  d.initial.T_world_body = MakeIsometry(so3::Exp(dtheta) * s0.R, s0.p + dp);
  d.initial.v_world_mps = s0.v + sig.velocity_mps * randn3();
  Eigen::Vector3d ba = sig.accel_bias_mps2 * randn3(), bg = sig.gyro_bias_radps * randn3();
  const double dt = 0.01;
  const int n = static_cast<int>(std::round(duration_s / dt));
  for (int k = 1; k <= n; ++k) {
    const double t = k * dt;
    ImuSample s = drive.PerfectImu(t, t0);
    ba += o.accel_bias_random_walk * std::sqrt(dt) * randn3();
    bg += o.gyro_bias_random_walk * std::sqrt(dt) * randn3();
    s.accel_mps2 += ba + o.accel_noise_density / std::sqrt(dt) * randn3();
    s.gyro_radps += bg + o.gyro_noise_density / std::sqrt(dt) * randn3();
    d.imu.push_back(s);
    if (k % 10 == 0) {
      const TruthState tr = drive.At(t);
      const Eigen::Vector3d p_ant =
          tr.p + tr.R * o.gnss.t_body_antenna +
          Eigen::Vector3d(0.02 * n01(rng), 0.02 * n01(rng), 0.03 * n01(rng));
      d.gnss.push_back(RtkFix(s.stamp, geo.ToGeodetic(p_ant).value(), 0.02, 0.03));
    }
  }
  return d;
}

}  // namespace slam_mms::testing
