#include "slam_mms/ins/ins_filter.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "ins/synthetic_drive.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/io/oxts_record.hpp"

namespace slam_mms {
namespace {

using testing::SyntheticDrive;
using testing::TruthState;

using testing::kOrigin;
using testing::kT0;

struct DriveConfig {
  double duration_s = 120.0;
  double imu_rate_hz = 100.0;
  double gnss_rate_hz = 10.0;
  bool noise = false;
  double outage_start_s = -1.0, outage_duration_s = 0.0;
  double jump_start_s = -1.0, jump_duration_s = 0.0, jump_m = 0.0;
  uint32_t seed = 1;
};

struct DriveResult {
  // Per 1 s epoch (after each second's GNSS update).
  std::vector<double> t_s, pos_err_m, att_err_deg, nees;
  int jump_fixes = 0, jump_fixes_rejected = 0;
  double max_interp_pos_err_m = 0.0, max_interp_att_err_deg = 0.0;
};

// An RTK-fixed fix (2 cm) of the antenna at `p`.
GnssFix RtkFixAt(Timestamp stamp, const GeodeticPoint& p) {
  return testing::RtkFix(stamp, p, 0.02, GnssFix().sigma_vertical_m);
}

InsFilter::Options FilterOptions() {
  InsFilter::Options o;
  o.gravity_mps2 = 9.80665;  // the generator's
  o.gnss.t_body_antenna = Eigen::Vector3d(0.5, 0.2, 1.2);
  o.init_sigma_position_m = 0.5;
  return o;
}

// Runs the filter along the analytic drive (world origin at kOrigin, so the first valid fix, the
// origin of the filter's world, is the truth's origin plus the first fix's noise: compare through
// WGS-84 as ARCHITECTURE.md asks, i.e. map the truth into the filter's world).
DriveResult RunDrive(const DriveConfig& cfg, InsFilter* filter) {
  const SyntheticDrive drive;
  const InsFilter::Options& o = filter->options();
  std::mt19937 rng(cfg.seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto randn3 = [&]() { return Eigen::Vector3d(n01(rng), n01(rng), n01(rng)); };
  GnssPrior truth_geo;  // converts truth ENU -> WGS-84
  EXPECT_TRUE(truth_geo.SetOrigin(kOrigin).ok());
  filter->mutable_gnss_prior().SetReferenceTime(kT0);
  if (cfg.outage_start_s >= 0.0) {
    EXPECT_TRUE(filter->mutable_gnss_prior()
                    .AddOutageWindow(cfg.outage_start_s, cfg.outage_duration_s)
                    .ok());
  }
  // Truth biases: constant offsets plus random walks (noisy drives only).
  Eigen::Vector3d ba = Eigen::Vector3d::Zero(), bg = Eigen::Vector3d::Zero();
  if (cfg.noise) {
    ba = 0.02 * randn3();
    bg = 2e-4 * randn3();
  }
  // Initial state: the truth, perturbed by the filter's initial sigmas for noisy drives.
  const TruthState s0 = drive.At(0.0);
  InsState init;
  init.stamp = kT0;
  Eigen::Vector3d dtheta = Eigen::Vector3d::Zero(), dp = Eigen::Vector3d::Zero(),
                  dv = Eigen::Vector3d::Zero();
  if (cfg.noise) {
    dp = o.init_sigma_position_m * randn3();
    dv = o.init_sigma_velocity_mps * randn3();
    dtheta = Eigen::Vector3d(o.init_sigma_roll_pitch_rad * n01(rng),
                             o.init_sigma_roll_pitch_rad * n01(rng),
                             o.init_sigma_yaw_rad * n01(rng));  // world axes
  }
  init.T_world_body = MakeIsometry(so3::Exp(dtheta) * s0.R, s0.p + dp);
  init.v_world_mps = s0.v + dv;
  EXPECT_TRUE(filter->Initialize(init).ok());
  // The filter's world must be the truth's: anchor it at the truth origin explicitly.
  EXPECT_TRUE(filter->mutable_gnss_prior().SetOrigin(kOrigin).ok());

  const Eigen::Vector3d& lever = o.gnss.t_body_antenna;
  const double sh = 0.02, sv = 0.03;
  DriveResult res;
  const int n_imu = static_cast<int>(std::round(cfg.duration_s * cfg.imu_rate_hz));
  const int imu_per_fix = static_cast<int>(std::round(cfg.imu_rate_hz / cfg.gnss_rate_hz));
  const double dt = 1.0 / cfg.imu_rate_hz;
  for (int k = 1; k <= n_imu; ++k) {
    const double t = k * dt;
    ImuSample s = drive.PerfectImu(t, kT0);
    if (cfg.noise) {
      ba += o.accel_bias_random_walk * std::sqrt(dt) * randn3();
      bg += o.gyro_bias_random_walk * std::sqrt(dt) * randn3();
      s.accel_mps2 += ba + o.accel_noise_density / std::sqrt(dt) * randn3();
      s.gyro_radps += bg + o.gyro_noise_density / std::sqrt(dt) * randn3();
    }
    EXPECT_TRUE(filter->AddImu(s).ok());
    const TruthState truth = drive.At(t);
    if (k % imu_per_fix == 0) {
      Eigen::Vector3d p_ant = truth.p + truth.R * lever;
      if (cfg.noise) p_ant += Eigen::Vector3d(sh * n01(rng), sh * n01(rng), sv * n01(rng));
      const bool jump = t >= cfg.jump_start_s && t < cfg.jump_start_s + cfg.jump_duration_s;
      if (jump) p_ant.x() += cfg.jump_m;
      const GnssFix fix = testing::RtkFix(s.stamp, truth_geo.ToGeodetic(p_ant).value(), sh, sv);
      auto r = filter->AddGnss(fix);
      EXPECT_TRUE(r.ok());
      if (jump) {
        ++res.jump_fixes;
        if (r.ok() && r->decision == GnssDecision::kReject) ++res.jump_fixes_rejected;
      }
    }
    if (k % static_cast<int>(cfg.imu_rate_hz) == 0) {
      const InsState est = filter->CurrentState().value();
      const Eigen::Matrix3d R = est.T_world_body.linear();
      Eigen::Matrix<double, 9, 1> e;
      e.segment<3>(0) = truth.p - est.T_world_body.translation();
      e.segment<3>(3) = truth.v - est.v_world_mps;
      e.segment<3>(6) = so3::Log(R.transpose() * truth.R);
      const Eigen::Matrix<double, 9, 9> P = filter->covariance().topLeftCorner<9, 9>();
      res.t_s.push_back(t);
      res.pos_err_m.push_back(e.head<3>().norm());
      res.att_err_deg.push_back(e.tail<3>().norm() * 180.0 / M_PI);
      res.nees.push_back(e.dot(P.ldlt().solve(e)));
      // Interpolated query between two states.
      const double tq = t - 0.5 * dt;
      const InsState q = filter->StateAt(kT0.PlusSeconds(tq)).value();
      const TruthState tr = drive.At(tq);
      res.max_interp_pos_err_m =
          std::max(res.max_interp_pos_err_m, (q.T_world_body.translation() - tr.p).norm());
      res.max_interp_att_err_deg =
          std::max(res.max_interp_att_err_deg,
                   RotationAngle(q.T_world_body.linear().transpose() * tr.R) * 180.0 / M_PI);
    }
  }
  return res;
}

double MaxIn(const DriveResult& r, const std::vector<double>& v, double t_a, double t_b) {
  double m = 0.0;
  for (size_t i = 0; i < v.size(); ++i) {
    if (r.t_s[i] >= t_a && r.t_s[i] < t_b) m = std::max(m, v[i]);
  }
  return m;
}

double RmsIn(const DriveResult& r, const std::vector<double>& v, double t_a, double t_b) {
  double s = 0.0;
  int n = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    if (r.t_s[i] >= t_a && r.t_s[i] < t_b) {
      s += v[i] * v[i];
      ++n;
    }
  }
  return n > 0 ? std::sqrt(s / n) : 0.0;
}

TEST(InsFilterTest, ZeroNoiseDriveReproducesTheTruth) {
  InsFilter filter = InsFilter::Create(FilterOptions()).value();
  DriveConfig cfg;
  cfg.duration_s = 120.0;
  const DriveResult r = RunDrive(cfg, &filter);
  ASSERT_EQ(r.t_s.size(), 120u);
  const double max_pos = MaxIn(r, r.pos_err_m, 0.0, 1e9);
  const double max_att = MaxIn(r, r.att_err_deg, 0.0, 1e9);
  std::printf(
      "zero-noise drive 120 s: max position error %.2e m, max attitude error %.2e deg, "
      "interpolated %.2e m %.2e deg\n",
      max_pos, max_att, r.max_interp_pos_err_m, r.max_interp_att_err_deg);
  EXPECT_LT(max_pos, 0.01);
  EXPECT_LT(max_att, 0.01);
  EXPECT_LT(r.max_interp_pos_err_m, 0.01);
  EXPECT_LT(r.max_interp_att_err_deg, 0.01);
  EXPECT_EQ(filter.gnss_prior().num_rejected(), 0);
}

TEST(InsFilterTest, NoisyDriveWithOutageIsConsistentAndRejectsAJump) {
  InsFilter filter = InsFilter::Create(FilterOptions()).value();
  DriveConfig cfg;
  cfg.duration_s = 300.0;
  cfg.noise = true;
  cfg.outage_start_s = 100.0;
  cfg.outage_duration_s = 60.0;
  cfg.jump_start_s = 220.0;
  cfg.jump_duration_s = 1.0;
  cfg.jump_m = 50.0;
  cfg.seed = 42;
  const DriveResult r = RunDrive(cfg, &filter);
  const double rms_before = RmsIn(r, r.pos_err_m, 20.0, 100.0);
  const double max_outage = MaxIn(r, r.pos_err_m, 100.0, 160.0);
  const double att_outage = MaxIn(r, r.att_err_deg, 100.0, 160.0);
  const double max_after = MaxIn(r, r.pos_err_m, 170.0, 300.1);
  const double rms_after = RmsIn(r, r.pos_err_m, 170.0, 300.1);
  const double max_jump = MaxIn(r, r.pos_err_m, 219.0, 230.0);
  int inside = 0, counted = 0;
  double nees_sum = 0.0;
  for (size_t i = 0; i < r.t_s.size(); ++i) {
    if (r.t_s[i] < 10.0) continue;
    ++counted;
    nees_sum += r.nees[i];
    // Two-sided 95 % interval of chi-square with 9 dof.
    if (r.nees[i] >= 2.700 && r.nees[i] <= 19.023) ++inside;
  }
  const double frac_inside = static_cast<double>(inside) / counted;
  std::printf(
      "noisy drive 300 s, outage [100, 160) s: position RMS before %.3f m; in the outage max %.3f "
      "m "
      "(attitude max %.4f deg); after (170-300 s) RMS %.3f m max %.3f m; around the 50 m jump max "
      "%.3f m; jump fixes rejected %d/%d; NEES mean %.2f (9 dof), %.1f %% of %d epochs inside "
      "[2.70, 19.02]\n",
      rms_before, max_outage, att_outage, rms_after, max_after, max_jump, r.jump_fixes_rejected,
      r.jump_fixes, nees_sum / counted, 100.0 * frac_inside, counted);
  EXPECT_EQ(r.jump_fixes, 10);
  EXPECT_EQ(r.jump_fixes_rejected, r.jump_fixes);
  EXPECT_LT(max_jump, 0.1);
  EXPECT_LT(rms_before, 0.05);
  EXPECT_LT(max_after, 0.1);
  EXPECT_GT(max_outage, rms_before);  // the outage drifts...
  EXPECT_LT(max_outage, 5.0);         // ...but a tactical IMU stays within metres over 60 s
  EXPECT_GE(frac_inside, 0.8);
  // Availability: the outage window is seen as an outage.
  EXPECT_EQ(filter.gnss_prior().AvailabilityAt(kT0.PlusSeconds(130.0)), GnssAvailability::kOutage);
  EXPECT_EQ(filter.gnss_prior().AvailabilityAt(kT0.PlusSeconds(90.0)), GnssAvailability::kValid);
  EXPECT_EQ(filter.gnss_prior().num_withheld(), 600);
}

TEST(InsFilterTest, CovarianceGrowsDuringTheOutage) {
  InsFilter filter = InsFilter::Create(FilterOptions()).value();
  DriveConfig cfg;
  cfg.duration_s = 60.0;
  cfg.noise = true;
  cfg.outage_start_s = 30.0;
  cfg.outage_duration_s = 60.0;
  RunDrive(cfg, &filter);
  const double sigma_end = std::sqrt(filter.covariance().block<3, 3>(0, 0).trace());
  const InsState at_start = filter.StateAt(kT0.PlusSeconds(29.9)).value();
  const double sigma_start = std::sqrt(at_start.cov_T_world_body.block<3, 3>(3, 3).trace());
  EXPECT_GT(sigma_end, 5.0 * sigma_start) << sigma_start << " " << sigma_end;
  // Monotone growth over the outage.
  double prev = 0.0;
  for (double t = 31.0; t < 60.0; t += 1.0) {
    const double s =
        filter.StateAt(kT0.PlusSeconds(t)).value().cov_T_world_body.block<3, 3>(3, 3).trace();
    EXPECT_GT(s, prev) << t;
    prev = s;
  }
}

// The drive's true state at t as an external POS record with covariance cov * I.
InsState TruePose(const SyntheticDrive& drive, double t, double cov) {
  const TruthState s = drive.At(t);
  InsState st;
  st.stamp = kT0.PlusSeconds(t);
  st.T_world_body = MakeIsometry(s.R, s.p);
  st.v_world_mps = s.v;
  st.cov_T_world_body = Matrix6d::Identity() * cov;
  return st;
}

TEST(InsFilterTest, ExternalPoseIsInterpolated) {
  InsFilter filter;
  const SyntheticDrive drive;
  for (int k = 0; k <= 100; ++k) {
    ASSERT_TRUE(filter.AddExternalPose(TruePose(drive, 0.1 * k, k % 2 == 0 ? 1e-4 : 3e-4)).ok());
  }
  EXPECT_FALSE(filter.AddImu(drive.PerfectImu(10.5, kT0)).ok());
  InsState dup;
  dup.stamp = kT0.PlusSeconds(5.0);
  EXPECT_FALSE(filter.AddExternalPose(dup).ok());  // out of order
  for (double t = 0.05; t < 10.0; t += 0.37) {
    const InsState q = filter.StateAt(kT0.PlusSeconds(t)).value();
    const TruthState s = drive.At(t);
    EXPECT_LT((q.T_world_body.translation() - s.p).norm(), 5e-3) << t;
    EXPECT_LT(RotationAngle(q.T_world_body.linear().transpose() * s.R), 1e-4) << t;
    EXPECT_GT(q.cov_T_world_body(0, 0), 0.99e-4);
    EXPECT_LT(q.cov_T_world_body(0, 0), 3.01e-4);
  }
  EXPECT_FALSE(filter.StateAt(kT0.PlusSeconds(-1.0)).ok());
  EXPECT_FALSE(filter.StateAt(kT0.PlusSeconds(11.0)).ok());
  EXPECT_EQ(filter.States().size(), 101u);
}

TEST(InsFilterTest, ForgettingOldStatesKeepsEveryLaterAnswer) {
  const SyntheticDrive drive;
  InsFilter full;
  InsFilter trimmed;
  for (int k = 0; k <= 100; ++k) {
    const InsState st = TruePose(drive, 0.1 * k, 1e-4 + 1e-6 * k);
    ASSERT_TRUE(full.AddExternalPose(st).ok());
    ASSERT_TRUE(trimmed.AddExternalPose(st).ok());
  }
  // 4.25 s lies between the states at 4.2 and 4.3 s: 4.2 s is kept, 4.1 s is not.
  const Timestamp t_keep = kT0.PlusSeconds(4.25);
  trimmed.ForgetStatesBefore(t_keep);
  EXPECT_EQ(trimmed.States().size(), 59u);  // 4.2 .. 10.0 s
  EXPECT_EQ(trimmed.States().front().stamp, kT0.PlusSeconds(0.1 * 42));
  for (double t = 4.25; t <= 10.1; t += 0.13) {
    const InsState a = full.StateAt(kT0.PlusSeconds(t)).value();
    const InsState b = trimmed.StateAt(kT0.PlusSeconds(t)).value();
    EXPECT_TRUE(a.T_world_body.isApprox(b.T_world_body, 0.0)) << t;
    EXPECT_EQ(a.cov_T_world_body, b.cov_T_world_body) << t;
  }
  EXPECT_EQ(trimmed.StateAt(kT0.PlusSeconds(4.1)).status().code(), StatusCode::kOutOfRange);
  // Never fewer than two states; a time after the last keeps the last two.
  trimmed.ForgetStatesBefore(kT0.PlusSeconds(60.0));
  EXPECT_EQ(trimmed.States().size(), 2u);
  EXPECT_TRUE(trimmed.StateAt(kT0.PlusSeconds(10.0)).ok());
}

TEST(InsFilterTest, StaticAlignmentAndGnssPositionInit) {
  InsFilter::Options o = FilterOptions();
  InsFilter filter = InsFilter::Create(o).value();
  const double roll = 0.035, pitch = -0.02, yaw = 1.1, g = 9.80665;
  const Eigen::Matrix3d R = FromRollPitchYaw(roll, pitch, yaw);
  const Eigen::Vector3d bg(1e-4, -2e-4, 5e-5);
  std::vector<ImuSample> samples;
  for (int k = 0; k < 200; ++k) {
    ImuSample s;
    s.stamp = kT0.PlusSeconds(0.01 * k);
    s.accel_mps2 = R.transpose() * Eigen::Vector3d(0, 0, g);
    s.gyro_radps = bg;
    samples.push_back(s);
  }
  ASSERT_TRUE(filter.InitializeStaticAlignment(samples, yaw).ok());
  EXPECT_FALSE(filter.initialized());
  GnssPrior geo;
  ASSERT_TRUE(geo.SetOrigin(kOrigin).ok());
  const Eigen::Vector3d p_body(3.0, 4.0, 0.5);
  const GeodeticPoint a = geo.ToGeodetic(p_body + R * o.gnss.t_body_antenna).value();
  filter.mutable_gnss_prior().SetReferenceTime(kT0);
  ASSERT_TRUE(filter.mutable_gnss_prior().SetOrigin(kOrigin).ok());
  ASSERT_TRUE(filter.AddGnss(RtkFixAt(kT0.PlusSeconds(2.0), a)).ok());
  ASSERT_TRUE(filter.initialized());
  const InsState s = filter.CurrentState().value();
  EXPECT_LT((s.T_world_body.translation() - p_body).norm(), 1e-6);
  EXPECT_LT(RotationAngle(s.T_world_body.linear().transpose() * R), 1e-9);
  EXPECT_LT((s.gyro_bias_radps - bg).norm(), 1e-12);
  // Staying still: the state stays put.
  for (int k = 1; k <= 500; ++k) {
    ImuSample m = samples.front();
    m.stamp = kT0.PlusSeconds(2.0 + 0.01 * k);
    ASSERT_TRUE(filter.AddImu(m).ok());
  }
  EXPECT_LT((filter.CurrentState().value().T_world_body.translation() - p_body).norm(), 1e-3);
  // Not gravity-like: refused.
  std::vector<ImuSample> moving = samples;
  for (auto& m : moving) m.accel_mps2 *= 3.0;
  EXPECT_FALSE(InsFilter().InitializeStaticAlignment(moving, 0.0).ok());
}

// The attitude given at t_a while turning; the first usable fix 3 s later. With the stamp the IMU
// carries attitude and velocity to the fix; without it they are 3 s stale (the KITTI-motion drives
// that start in a turn began with ~20 deg of heading error).
TEST(InsFilterTest, StampedAttitudeIsCarriedToTheFirstFix) {
  const testing::SyntheticDrive drive;
  const double t_a = 12.0, t_fix = 15.0;  // a turn of a few deg/s
  const testing::TruthState a = drive.At(t_a), f = drive.At(t_fix);
  GnssPrior geo;
  ASSERT_TRUE(geo.SetOrigin(kOrigin).ok());
  double heading_err_deg[2] = {0, 0}, vel_err[2] = {0, 0};
  for (int with_stamp = 0; with_stamp < 2; ++with_stamp) {
    InsFilter::Options o = FilterOptions();
    InsFilter filter = InsFilter::Create(o).value();
    filter.mutable_gnss_prior().SetReferenceTime(kT0);
    ASSERT_TRUE(filter.mutable_gnss_prior().SetOrigin(kOrigin).ok());
    const std::optional<Timestamp> stamp =
        with_stamp ? std::optional<Timestamp>(kT0.PlusSeconds(t_a)) : std::nullopt;
    ASSERT_TRUE(filter.InitializeAttitude(Eigen::Quaterniond(a.R), a.v, stamp).ok());
    for (double t = t_a; t < t_fix - 1e-9; t += 0.01) {
      ASSERT_TRUE(filter.AddImu(drive.PerfectImu(t, kT0)).ok());
    }
    const GeodeticPoint g = geo.ToGeodetic(f.p + f.R * o.gnss.t_body_antenna).value();
    ASSERT_TRUE(filter.AddGnss(RtkFixAt(kT0.PlusSeconds(t_fix), g)).ok());
    ASSERT_TRUE(filter.initialized());
    const InsState s = filter.CurrentState().value();
    heading_err_deg[with_stamp] =
        RotationAngle(s.T_world_body.linear().transpose() * f.R) * 180.0 / M_PI;
    vel_err[with_stamp] = (s.v_world_mps - f.v).norm();
  }
  std::printf("attitude error at the first fix: %.3f deg unstamped, %.4f deg stamped\n",
              heading_err_deg[0], heading_err_deg[1]);
  EXPECT_GT(heading_err_deg[0], 3.0);  // the drive turns: a stale attitude is far off
  EXPECT_LT(heading_err_deg[1], 0.05);
  EXPECT_LT(vel_err[1], 0.05);
}

// An OXTS record at Karlsruhe, RTK fixed (5 cm), level, heading yaw_rad, standing.
OxtsRecord RtkFixedRecord(double yaw_rad) {
  OxtsRecord rec;
  rec.lat_deg = 49.011;
  rec.lon_deg = 8.4165;
  rec.alt_m = 112.0;
  rec.yaw_rad = yaw_rad;
  rec.pos_accuracy_m = 0.05;
  rec.navstat = kOxtsNavstatLocked;
  rec.posmode = 6;
  return rec;
}

TEST(InsFilterTest, InitializeFromOxtsRecord) {
  InsFilter filter;
  OxtsRecord rec = RtkFixedRecord(2.0);
  rec.roll_rad = 0.01;
  rec.pitch_rad = -0.02;
  rec.vn = 3.0;
  rec.ve = 4.0;
  // The OXTS adapter (io): attitude and velocity, then the record's own fix sets the position.
  ASSERT_TRUE(
      filter.InitializeAttitude(Eigen::Quaterniond(OxtsAttitude(rec)), OxtsVelocityEnu(rec)).ok());
  ASSERT_TRUE(filter.AddGnss(ToGnssFix(rec, kT0)).ok());
  ASSERT_TRUE(filter.initialized());
  const InsState s = filter.CurrentState().value();
  EXPECT_LT(s.T_world_body.translation().norm(), 1e-9);  // origin at the fix, no lever arm
  EXPECT_LT(RotationAngle(s.T_world_body.linear().transpose() * OxtsAttitude(rec)), 1e-9);
  EXPECT_LT((s.v_world_mps - Eigen::Vector3d(4.0, 3.0, 0.0)).norm(), 1e-12);
  // Somigliana gravity at 49 deg N, 112 m: about 9.8095.
  EXPECT_NEAR(-filter.gravity_world().z(), InsFilter::NormalGravity(49.011, 112.0), 1e-12);
  EXPECT_NEAR(InsFilter::NormalGravity(49.011, 112.0), 9.8095, 5e-4);
  EXPECT_NEAR(InsFilter::NormalGravity(0.0, 0.0), 9.7803253359, 1e-9);
}

// An initial attitude of stated accuracy (an OXTS record: KittiDriveReader) starts the filter
// with that accuracy, grown by the unobserved gyro bias over the IMU carry to the first fix;
// without it the options' init sigmas hold. Roll, pitch, yaw about the world axes.
TEST(InsFilterTest, StatedInitialAttitudeSigma) {
  const OxtsRecord rec = RtkFixedRecord(0.7);
  const Eigen::Matrix3d R = OxtsAttitude(rec);
  const Eigen::Vector3d stated = Eigen::Vector3d(0.03, 0.03, 0.1) * (M_PI / 180.0);
  InsFilter::Options o;
  o.use_stated_attitude_sigma = true;
  // carry_s: the first fix that long after the attitude's stamp, the vehicle standing meanwhile.
  auto world_sigmas = [&](std::optional<Eigen::Vector3d> sigma, double carry_s) {
    InsFilter filter = InsFilter::Create(o).value();
    EXPECT_TRUE(
        filter.InitializeAttitude(Eigen::Quaterniond(R), Eigen::Vector3d::Zero(), kT0, sigma).ok());
    for (double t = 0.01; t < carry_s - 1e-9; t += 0.01) {
      ImuSample imu;
      imu.stamp = kT0.PlusSeconds(t);
      imu.accel_mps2 = R.transpose() * Eigen::Vector3d(0.0, 0.0, 9.8095);
      EXPECT_TRUE(filter.AddImu(imu).ok());
    }
    EXPECT_TRUE(filter.AddGnss(ToGnssFix(rec, kT0.PlusSeconds(carry_s))).ok());
    EXPECT_TRUE(filter.initialized());
    const Eigen::Matrix3d C_body =
        filter.CurrentState().value().cov_T_world_body.topLeftCorner<3, 3>();
    return Eigen::Vector3d((R * C_body * R.transpose()).diagonal().cwiseSqrt());
  };
  const Eigen::Vector3d at_once = world_sigmas(stated, 0.0);
  EXPECT_LT((at_once - stated).cwiseAbs().maxCoeff(), 1e-9) << at_once.transpose();
  const Eigen::Vector3d carried = world_sigmas(stated, 1.0);
  const double drift = o.init_sigma_gyro_bias_radps * 1.0;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(carried[k], std::hypot(stated[k], drift), 1e-5 * stated[k]) << k;
  }
  const Eigen::Vector3d unknown = world_sigmas(std::nullopt, 0.0);
  EXPECT_NEAR(unknown[0], o.init_sigma_roll_pitch_rad, 1e-12);
  EXPECT_NEAR(unknown[1], o.init_sigma_roll_pitch_rad, 1e-12);
  EXPECT_NEAR(unknown[2], o.init_sigma_yaw_rad, 1e-12);
  // Off: the stated sigma is ignored (on by default since session 42).
  o.use_stated_attitude_sigma = false;
  const Eigen::Vector3d ignored = world_sigmas(stated, 0.0);
  EXPECT_LT((ignored - unknown).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_TRUE(InsFilter::Options().use_stated_attitude_sigma);
  // A sigma that is not finite and positive is refused, naming it.
  InsFilter filter;
  for (const Eigen::Vector3d& bad :
       {Eigen::Vector3d(0.0, 1e-3, 1e-3), Eigen::Vector3d(1e-3, -1e-3, 1e-3),
        Eigen::Vector3d(1e-3, 1e-3, std::nan(""))}) {
    const Status s =
        filter.InitializeAttitude(Eigen::Quaterniond(R), Eigen::Vector3d::Zero(), kT0, bad);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("sigma_rpy_rad"), std::string::npos) << s.message();
  }
}

TEST(InsFilterTest, OptionsAreValidated) {
  InsFilter::Options o;
  o.accel_noise_density = 0.0;
  const Status s = InsFilter::Create(o).status();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("accel_noise_density"), std::string::npos);
  o = InsFilter::Options();
  o.gnss.outage_timeout_s = -1.0;
  EXPECT_FALSE(InsFilter::Create(o).ok());
  InsFilter f;
  EXPECT_FALSE(f.CurrentState().ok());
  EXPECT_FALSE(f.StateAt(kT0).ok());
}

}  // namespace
}  // namespace slam_mms
