// ReferenceTrajectory: analytic derivatives and the IMU they produce are consistent with the poses.
#include "slam_mms/sim/reference_trajectory.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/sim/imu_simulator.hpp"

namespace slam_mms::sim {
namespace {

ReferenceTrajectory DefaultTrajectory() {
  auto traj = ReferenceTrajectory::Fit(Timestamp::FromSeconds(1.7e9), DefaultUrbanRouteSamples(),
                                       ReferenceTrajectory::FitOptions());
  EXPECT_TRUE(traj.ok()) << traj.status().ToString();
  return *traj;
}

TEST(ReferenceTrajectoryTest, DefaultRouteIsAFewMinutesWithALoop) {
  const auto samples = DefaultUrbanRouteSamples();
  ASSERT_GT(samples.size(), 100u);
  const double duration = samples.back().t_s - samples.front().t_s;
  EXPECT_GT(duration, 120.0);
  EXPECT_LT(duration, 300.0);
  const ReferenceTrajectory traj = DefaultTrajectory();
  EXPECT_GT(traj.PathLength(), 1200.0);
  // The fit follows the route samples closely.
  double max_err = 0.0;
  for (const auto& s : samples)
    max_err = std::max(max_err, (traj.Pose(s.t_s).translation() - s.p_world).norm());
  EXPECT_LT(max_err, 0.15);
  // The loop: a later part of the drive passes within 1 m of the start street, > 60 s later.
  const Eigen::Vector3d p10 = traj.Pose(12.0).translation();
  bool revisited = false;
  for (double t = 80.0; t < traj.end_s(); t += 0.1)
    revisited |= (traj.Pose(t).translation() - p10).head<2>().norm() < 1.0;
  EXPECT_TRUE(revisited);
  // Stops: the speed falls to zero somewhere in the middle of the drive.
  int stopped_samples = 0;
  for (double t = 20.0; t < traj.end_s() - 5.0; t += 0.1)
    stopped_samples += traj.Evaluate(t).v_world_mps.norm() < 0.05 ? 1 : 0;
  EXPECT_GT(stopped_samples, 50);
}

TEST(ReferenceTrajectoryTest, LongRouteLastsAtLeastTheDurationAndExploresNewStreets) {
  for (double duration : {60.0, 1800.0}) {
    const auto samples = LongUrbanRouteSamples(duration);
    ASSERT_GT(samples.size(), 100u);
    const double span = samples.back().t_s - samples.front().t_s;
    EXPECT_GE(span, duration);
    EXPECT_LT(span, duration + 150.0);  // at most one more street and block
    auto traj = ReferenceTrajectory::Fit(Timestamp::FromSeconds(1.7e9), samples,
                                         ReferenceTrajectory::FitOptions());
    ASSERT_TRUE(traj.ok()) << traj.status().ToString();
    // Never back to an earlier place: a point 60 s later is > 100 m from every earlier one's
    // street, checked on a coarse grid of times.
    double min_gap = 1e9;
    for (double t0 = 5.0; t0 + 60.0 < traj->end_s(); t0 += 20.0) {
      for (double t1 = t0 + 60.0; t1 < traj->end_s(); t1 += 20.0) {
        min_gap = std::min(
            min_gap,
            (traj->Pose(t1).translation() - traj->Pose(t0).translation()).head<2>().norm());
      }
    }
    EXPECT_GT(min_gap, 50.0) << duration;
    for (const auto& s : samples) ASSERT_TRUE(s.p_world.allFinite() && s.rpy_rad.allFinite());
  }
}

TEST(ReferenceTrajectoryTest, DerivativesMatchFiniteDifferences) {
  const ReferenceTrajectory traj = DefaultTrajectory();
  const double h = 1e-4;
  for (double t = 5.037; t < traj.end_s() - 1.0; t += 7.3) {  // off the knots (jerk jumps there)
    const BodyState s = traj.Evaluate(t);
    const Eigen::Vector3d v_fd =
        (traj.Pose(t + h).translation() - traj.Pose(t - h).translation()) / (2 * h);
    EXPECT_LT((v_fd - s.v_world_mps).norm(), 1e-5) << "t=" << t;
    const Eigen::Vector3d a_fd =
        (traj.Evaluate(t + h).v_world_mps - traj.Evaluate(t - h).v_world_mps) / (2 * h);
    EXPECT_LT((a_fd - s.a_world_mps2).norm(), 1e-4) << "t=" << t;
    const Eigen::Vector3d w_fd =
        so3::Log(traj.Pose(t - h).linear().transpose() * traj.Pose(t + h).linear()) / (2 * h);
    EXPECT_LT((w_fd - s.omega_body_radps).norm(), 1e-6) << "t=" << t;
  }
}

// Catmull-Rom interpolation of uniformly sampled vectors at fractional index x.
Eigen::Vector3d Interp(const std::vector<Eigen::Vector3d>& y, double x) {
  const int i = std::clamp(static_cast<int>(std::floor(x)), 1, static_cast<int>(y.size()) - 3);
  const double u = x - i;
  const Eigen::Vector3d &p0 = y[i - 1], &p1 = y[i], &p2 = y[i + 1], &p3 = y[i + 2];
  return 0.5 * ((2 * p1) + (-p0 + p2) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u * u +
                (-p0 + 3 * p1 - 3 * p2 + p3) * u * u * u);
}

TEST(ReferenceTrajectoryTest, ZeroNoiseImuIntegratesBackOntoGroundTruth) {
  const ReferenceTrajectory traj = DefaultTrajectory();
  const double g = 9.81, dt = 0.01;
  ImuSimulator imu(ImuSimulator::Options::ForGrade(ImuGrade::kPerfect), 7);
  // 10 s through the first corner (turn, braking and acceleration).
  const double t0 = 28.0;
  const int n = 1000;
  std::vector<Eigen::Vector3d> f, w;
  for (int k = -1; k <= n + 2; ++k) {
    const double t = t0 + k * dt;
    const ImuSample m = imu.Measure(traj.Evaluate(t), traj.ToTimestamp(t));
    f.push_back(m.accel_mps2);
    w.push_back(m.gyro_radps);
  }
  double max_yaw_rate = 0.0;
  for (const auto& x : w) max_yaw_rate = std::max(max_yaw_rate, std::abs(x.z()));
  EXPECT_GT(max_yaw_rate, 0.3) << "the window must contain a turn";
  // RK4 strapdown integration of the samples (values between samples by Catmull-Rom).
  const BodyState s0 = traj.Evaluate(t0);
  Eigen::Quaterniond q(s0.T_world_body.linear());
  Eigen::Vector3d v = s0.v_world_mps, p = s0.T_world_body.translation();
  const Eigen::Vector3d gw(0, 0, -g);
  struct D {
    Eigen::Vector4d dq;
    Eigen::Vector3d dv, dp;
  };
  auto deriv = [&](const Eigen::Quaterniond& qq, const Eigen::Vector3d& vv, double x) {
    const Eigen::Vector3d wi = Interp(w, x + 1), fi = Interp(f, x + 1);
    const Eigen::Quaterniond dq = qq * Eigen::Quaterniond(0, wi.x(), wi.y(), wi.z());
    D d;
    d.dq = 0.5 * dq.coeffs();
    d.dv = qq.normalized() * fi + gw;
    d.dp = vv;
    return d;
  };
  double max_err = 0.0;
  for (int k = 0; k < n; ++k) {
    auto add = [](const Eigen::Quaterniond& a, const Eigen::Vector4d& d, double s) {
      return Eigen::Quaterniond(Eigen::Vector4d(a.coeffs() + s * d));
    };
    const D k1 = deriv(q, v, k);
    const D k2 = deriv(add(q, k1.dq, dt / 2), v + dt / 2 * k1.dv, k + 0.5);
    const D k3 = deriv(add(q, k2.dq, dt / 2), v + dt / 2 * k2.dv, k + 0.5);
    const D k4 = deriv(add(q, k3.dq, dt), v + dt * k3.dv, k + 1.0);
    q = add(q, (k1.dq + 2 * k2.dq + 2 * k3.dq + k4.dq) / 6.0, dt).normalized();
    p += dt / 6.0 * (k1.dp + 2 * k2.dp + 2 * k3.dp + k4.dp);
    v += dt / 6.0 * (k1.dv + 2 * k2.dv + 2 * k3.dv + k4.dv);
    max_err = std::max(max_err, (p - traj.Pose(t0 + (k + 1) * dt).translation()).norm());
  }
  const Eigen::Isometry3d T_end = traj.Pose(t0 + n * dt);
  EXPECT_LT(max_err, 0.01) << "position error over 10 s";
  EXPECT_LT(RotationAngle(q.toRotationMatrix().transpose() * T_end.linear()), 1e-4);
  RecordProperty("max_position_error_m", std::to_string(max_err));
}

// A car driving east at 10 m/s whose recorded positions jump 0.4 m to the left at 10 s (a GNSS
// re-fix) while its recorded velocities stay straight: fitted through the positions alone the
// car moves sideways at metres per second; with the velocities and 1 m positions it does not.
// Over minutes the positions still hold the motion: a velocity biased 0.05 m/s to the north for
// 200 s (10 m integrated) stays within a few metres of the positions.
TEST(ReferenceTrajectoryTest, VelocitiesHoldTheMotionWherePositionsJump) {
  std::vector<PoseSample> samples;
  for (int i = 0; i <= 2000; ++i) {
    PoseSample s;
    s.t_s = 0.1 * i;
    s.p_world = Eigen::Vector3d(1.0 * i, s.t_s >= 10.0 ? 0.4 : 0.0, 0.0);
    s.v_world_mps = Eigen::Vector3d(10.0, s.t_s >= 30.0 ? 0.05 : 0.0, 0.0);
    samples.push_back(s);
  }
  auto max_sideways = [](const ReferenceTrajectory& traj, double from_s, double to_s) {
    double m = 0.0;
    for (double t = from_s; t <= to_s; t += 0.01) {
      m = std::max(m, std::abs(traj.Evaluate(t).v_world_mps.y()));
    }
    return m;
  };
  ReferenceTrajectory::FitOptions options;
  auto through_positions = ReferenceTrajectory::Fit(Timestamp(), samples, options);
  ASSERT_TRUE(through_positions.ok()) << through_positions.status().ToString();
  EXPECT_GT(max_sideways(*through_positions, 9.0, 11.0), 1.0);

  for (PoseSample& s : samples) {
    s.has_velocity = true;
    s.position_sigma_m = 1.0;
  }
  auto with_velocities = ReferenceTrajectory::Fit(Timestamp(), samples, options);
  ASSERT_TRUE(with_velocities.ok()) << with_velocities.status().ToString();
  EXPECT_LT(max_sideways(*with_velocities, 1.0, 29.0), 0.03);
  // The bias: sideways motion near 0.05 m/s, the positions pulling it back only slowly.
  EXPECT_LT(max_sideways(*with_velocities, 31.0, 199.0), 0.08);
  double max_off = 0.0;
  for (const PoseSample& s : samples) {
    max_off = std::max(max_off, (with_velocities->Pose(s.t_s).translation() - s.p_world).norm());
  }
  EXPECT_LT(max_off, 4.0);  // 8.5 m where the velocities alone were integrated
  EXPECT_GT(max_off, 0.5);  // and not the positions themselves

  // A sample whose own sigma is the options' is fitted exactly as one without its own.
  std::vector<PoseSample> plain = DefaultUrbanRouteSamples(), own = plain;
  for (PoseSample& s : own) s.position_sigma_m = options.position_sigma_m;
  auto a = ReferenceTrajectory::Fit(Timestamp(), plain, options);
  auto b = ReferenceTrajectory::Fit(Timestamp(), own, options);
  ASSERT_TRUE(a.ok() && b.ok());
  for (double t = 0.0; t < a->end_s(); t += 7.3) {
    EXPECT_EQ(a->Pose(t).matrix(), b->Pose(t).matrix()) << t;
  }
}

TEST(ReferenceTrajectoryTest, RestrictedIsTheSameMotionOverItsSpan) {
  const ReferenceTrajectory full = DefaultTrajectory();
  auto part = full.Restricted(20.03, 35.0);
  ASSERT_TRUE(part.ok()) << part.status().ToString();
  EXPECT_LE(part->start_s(), 20.03);
  EXPECT_GT(part->start_s(), 19.9);
  EXPECT_GE(part->end_s(), 35.0);
  EXPECT_LT(part->end_s(), 35.11);
  for (double t = 20.03; t <= 35.0; t += 0.37) {
    const BodyState a = full.Evaluate(t), b = part->Evaluate(t);
    EXPECT_LT((a.T_world_body.matrix() - b.T_world_body.matrix()).norm(), 1e-12) << t;
    EXPECT_LT((a.v_world_mps - b.v_world_mps).norm(), 1e-12) << t;
    EXPECT_LT((a.omega_body_radps - b.omega_body_radps).norm(), 1e-12) << t;
  }
  EXPECT_FALSE(full.Restricted(full.end_s() + 1.0, full.end_s() + 2.0).ok());
  EXPECT_FALSE(full.Restricted(30.0, 30.0).ok());
  auto whole = full.Restricted(-1e9, 1e9);
  ASSERT_TRUE(whole.ok());
  EXPECT_EQ(whole->start_s(), full.start_s());
  EXPECT_EQ(whole->end_s(), full.end_s());
}

// A car heading north-east: a sideways slide of 2 m/s for 0.3 s, and 1.2 s later a fall of 4 m/s,
// are two spans; a slower slide, and samples without velocities, are none.
TEST(ReferenceTrajectoryTest, ImplausibleMotionIsFoundWhereTheVelocityIsNotACars) {
  std::vector<PoseSample> samples;
  const double yaw = M_PI / 4.0;
  const Eigen::Vector3d forward(std::cos(yaw), std::sin(yaw), 0.0);
  const Eigen::Vector3d left(-std::sin(yaw), std::cos(yaw), 0.0);
  for (int i = 0; i < 60; ++i) {
    PoseSample s;
    s.t_s = 0.1 * i;
    s.rpy_rad.z() = yaw;
    s.has_velocity = true;
    s.record = 100 + i;
    s.v_world_mps = 10.0 * forward + 0.3 * left;
    if (i >= 10 && i <= 12) s.v_world_mps += 2.0 * left;
    if (i >= 25 && i <= 27) s.v_world_mps.z() = -4.0;
    samples.push_back(s);
  }
  const std::vector<ImplausibleMotion> spans = FindImplausibleMotion(samples);
  ASSERT_EQ(spans.size(), 2u);
  EXPECT_NEAR(spans[0].from_s, 1.0, 1e-9);
  EXPECT_NEAR(spans[0].to_s, 1.2, 1e-9);
  EXPECT_EQ(spans[0].first_record, 110);
  EXPECT_EQ(spans[0].last_record, 112);
  EXPECT_NEAR(spans[0].max_sideways_mps, 2.3, 1e-9);
  EXPECT_NEAR(spans[0].max_vertical_mps, 0.0, 1e-9);
  EXPECT_EQ(spans[1].first_sample, 25u);
  EXPECT_EQ(spans[1].last_sample, 27u);
  EXPECT_NEAR(spans[1].max_vertical_mps, 4.0, 1e-9);
  // Closer than 1 s: one span.
  samples[20].v_world_mps.z() = 5.0;
  EXPECT_EQ(FindImplausibleMotion(samples).size(), 1u);
  for (PoseSample& s : samples) s.has_velocity = false;
  EXPECT_TRUE(FindImplausibleMotion(samples).empty());
}

TEST(ReferenceTrajectoryTest, FitRejectsBadInput) {
  std::vector<PoseSample> few(3);
  EXPECT_FALSE(ReferenceTrajectory::Fit(Timestamp(), few, {}).ok());
  ReferenceTrajectory::FitOptions o;
  o.knot_spacing_s = 0.0;
  EXPECT_FALSE(o.Validate().ok());
  o = {};
  o.velocity_sigma_mps = 0.0;
  EXPECT_FALSE(o.Validate().ok());
  std::vector<PoseSample> samples(8);
  for (int i = 0; i < 8; ++i) samples[i].t_s = 0.1 * i;
  samples[3].position_sigma_m = -1.0;
  EXPECT_FALSE(ReferenceTrajectory::Fit(Timestamp(), samples, {}).ok());
  samples[3].position_sigma_m = 0.0;
  samples[4].has_velocity = true;
  samples[4].v_world_mps.x() = std::nan("");
  EXPECT_FALSE(ReferenceTrajectory::Fit(Timestamp(), samples, {}).ok());
  samples[4].v_world_mps.x() = 1.0;
  EXPECT_TRUE(ReferenceTrajectory::Fit(Timestamp(), samples, {}).ok());
}

}  // namespace
}  // namespace slam_mms::sim
