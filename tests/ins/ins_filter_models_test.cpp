// InsFilter's error and motion models (issue 17, "a proper forward filter"): time-correlated GNSS
// errors as Gauss-Markov bias states (a fixed -> float bias step does not leak into the tilt; the
// position covariance stays consistent under correlated float errors, where a white-noise model is
// overconfident), zero-velocity updates while standing (and released when the vehicle starts), and
// the optional non-holonomic constraint in an outage.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <random>

#include "ins/synthetic_drive.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"
#include "slam_mms/ins/ins_filter.hpp"

namespace slam_mms {
namespace {

using testing::SyntheticDrive;
using testing::TruthState;

using testing::kOrigin;
using testing::kT0;
constexpr double kG = 9.80665;

using Truth = std::function<TruthState(double t)>;

// The GNSS receiver at time t: available or not, its solution type and reported sigmas.
struct ReceiverState {
  bool available = true;
  GnssFixType type = GnssFixType::kRtkFixed;
  double sigma_h = 0.02, sigma_v = 0.03;
};
using Receiver = std::function<ReceiverState(double t)>;

// The true GNSS error process of the test receiver: per solution type a share `rho` of the
// reported variance is a first-order Gauss-Markov bias with correlation time `tau`, redrawn from
// its stationary distribution when the solution type changes; the rest is white.
struct ErrorProcess {
  double rho_fixed = 0.0, tau_fixed = 30.0;
  double rho_float = 0.9, tau_float = 30.0;
  double rho_code = 0.9, tau_code = 60.0;
};

struct DriveRun {
  std::vector<double> t, pos_err, tilt_deg, yaw_deg, nees_pos, speed_err, up_err;
  int zupts_at_20s = -1;
};

InsFilter::Options BaseOptions() {
  InsFilter::Options o;
  o.gravity_mps2 = kG;
  o.gnss.t_body_antenna = Eigen::Vector3d(0.5, 0.2, 1.2);
  o.init_sigma_position_m = 0.5;
  return o;
}

// The IMU is drawn from the filter's own noise model, or from `imu` where given (its datasheet:
// turn-on biases, Gauss-Markov drift, white noise).
DriveRun RunModelDrive(const Truth& truth, double duration_s, const Receiver& receiver,
                       const ErrorProcess& ep, InsFilter* filter, uint32_t seed,
                       const ImuNoiseSpec* imu = nullptr) {
  const InsFilter::Options& o = filter->options();
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto randn3 = [&]() { return Eigen::Vector3d(n01(rng), n01(rng), n01(rng)); };
  const double gyro_density = imu ? imu->gyro_noise_density : o.gyro_noise_density;
  const double accel_density = imu ? imu->accel_noise_density : o.accel_noise_density;
  GnssPrior truth_geo;
  EXPECT_TRUE(truth_geo.SetOrigin(kOrigin).ok());
  filter->mutable_gnss_prior().SetReferenceTime(kT0);
  Eigen::Vector3d ba = 0.02 * randn3(), bg = 2e-4 * randn3();
  Eigen::Vector3d ba_gm = Eigen::Vector3d::Zero(), bg_gm = Eigen::Vector3d::Zero();
  if (imu) {
    ba = imu->accel_turn_on_bias_sigma * randn3();
    bg = imu->gyro_turn_on_bias_sigma * randn3();
    ba_gm = imu->accel_bias_instability * randn3();
    bg_gm = imu->gyro_bias_instability * randn3();
  }
  const TruthState s0 = truth(0.0);
  InsState init;
  init.stamp = kT0;
  const Eigen::Vector3d dtheta(o.init_sigma_roll_pitch_rad * n01(rng),
                               o.init_sigma_roll_pitch_rad * n01(rng),
                               o.init_sigma_yaw_rad * n01(rng));
  init.T_world_body = MakeIsometry(so3::Exp(dtheta) * s0.R, s0.p + 0.1 * randn3());
  init.v_world_mps = s0.v + 0.02 * randn3();
  EXPECT_TRUE(filter->Initialize(init).ok());
  EXPECT_TRUE(filter->mutable_gnss_prior().SetOrigin(kOrigin).ok());

  const Eigen::Vector3d& lever = o.gnss.t_body_antenna;
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  GnssFixType last_type = GnssFixType::kNone;
  DriveRun run;
  const double dt = 0.01;
  const int n = static_cast<int>(std::round(duration_s / dt));
  for (int k = 1; k <= n; ++k) {
    const double t = k * dt;
    const TruthState tr = truth(t);
    ImuSample s;
    s.stamp = kT0.PlusSeconds(t);
    if (imu) {
      const double ea = std::exp(-dt / imu->accel_bias_correlation_time_s);
      const double eg = std::exp(-dt / imu->gyro_bias_correlation_time_s);
      ba_gm = ea * ba_gm + imu->accel_bias_instability * std::sqrt(1.0 - ea * ea) * randn3();
      bg_gm = eg * bg_gm + imu->gyro_bias_instability * std::sqrt(1.0 - eg * eg) * randn3();
    } else {
      ba += o.accel_bias_random_walk * std::sqrt(dt) * randn3();
      bg += o.gyro_bias_random_walk * std::sqrt(dt) * randn3();
    }
    s.accel_mps2 = tr.f_body + ba + ba_gm + accel_density / std::sqrt(dt) * randn3();
    s.gyro_radps = tr.w_body + bg + bg_gm + gyro_density / std::sqrt(dt) * randn3();
    EXPECT_TRUE(filter->AddImu(s).ok());
    if (k % 10 == 0) {
      const ReceiverState rs = receiver(t);
      if (rs.available) {
        const bool fixed = rs.type == GnssFixType::kRtkFixed;
        const bool is_float = rs.type == GnssFixType::kRtkFloat;
        const double rho = fixed ? ep.rho_fixed : is_float ? ep.rho_float : ep.rho_code;
        const double tau = fixed ? ep.tau_fixed : is_float ? ep.tau_float : ep.tau_code;
        const Eigen::Vector3d sigma(rs.sigma_h, rs.sigma_h, rs.sigma_v);
        if (rs.type != last_type) {
          bias = std::sqrt(rho) * sigma.cwiseProduct(randn3());
        } else {
          const double e = std::exp(-0.1 / tau);
          bias = e * bias + std::sqrt(rho * (1.0 - e * e)) * sigma.cwiseProduct(randn3());
        }
        last_type = rs.type;
        const Eigen::Vector3d white = std::sqrt(1.0 - rho) * sigma.cwiseProduct(randn3());
        const GeodeticPoint g = truth_geo.ToGeodetic(tr.p + tr.R * lever + bias + white).value();
        GnssFix fix;
        fix.stamp = s.stamp;
        fix.latitude_deg = g.latitude_deg;
        fix.longitude_deg = g.longitude_deg;
        fix.height_m = g.height_m;
        fix.sigma_horizontal_m = rs.sigma_h;
        fix.sigma_vertical_m = rs.sigma_v;
        fix.type = rs.type;
        EXPECT_TRUE(filter->AddGnss(fix).ok());
      }
    }
    if (k == 2000) run.zupts_at_20s = filter->num_zero_velocity_updates();
    if (k % 100 == 0) {
      const InsState est = filter->CurrentState().value();
      const Eigen::Vector3d dp = tr.p - est.T_world_body.translation();
      // Attitude error in world axes: R_true = Exp(e) R_est.
      const Eigen::Vector3d e = so3::Log(tr.R * est.T_world_body.linear().transpose());
      const Eigen::Matrix3d Pp = filter->covariance().block<3, 3>(0, 0);
      run.t.push_back(t);
      run.pos_err.push_back(dp.norm());
      run.tilt_deg.push_back(e.head<2>().norm() * 180.0 / M_PI);
      run.yaw_deg.push_back(e.z() * 180.0 / M_PI);
      run.nees_pos.push_back(dp.dot(Pp.ldlt().solve(dp)));
      run.speed_err.push_back((tr.v - est.v_world_mps).norm());
      run.up_err.push_back(std::abs(dp.z()));
    }
  }
  return run;
}

double MaxIn(const DriveRun& r, const std::vector<double>& v, double a, double b) {
  double m = 0.0;
  for (size_t i = 0; i < v.size(); ++i)
    if (r.t[i] >= a && r.t[i] < b) m = std::max(m, std::abs(v[i]));
  return m;
}

double RmsIn(const DriveRun& r, const std::vector<double>& v, double a, double b) {
  double ss = 0.0;
  int n = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    if (r.t[i] >= a && r.t[i] < b) {
      ss += v[i] * v[i];
      ++n;
    }
  }
  return n > 0 ? std::sqrt(ss / n) : 0.0;
}

// The mean of v over the epochs in [a, b) (0 where there are none).
double MeanIn(const DriveRun& r, const std::vector<double>& v, double a, double b) {
  double sum = 0.0;
  int n = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    if (r.t[i] >= a && r.t[i] < b) {
      sum += v[i];
      ++n;
    }
  }
  return n > 0 ? sum / n : 0.0;
}

// Position NEES (3 dof) and error from `from_s` on: the mean NEES, the share of epochs inside
// the two-sided 99 % interval of chi-square with 3 dof, and the error's RMS [m].
struct PositionConsistency {
  double nees_mean = 0.0, inside_99 = 0.0, error_rms_m = 0.0;
};
PositionConsistency PositionConsistencyFrom(const DriveRun& r, double from_s) {
  int in = 0, cnt = 0;
  double sum = 0.0, sq = 0.0;
  for (size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] < from_s) continue;
    ++cnt;
    sum += r.nees_pos[i];
    sq += r.pos_err[i] * r.pos_err[i];
    if (r.nees_pos[i] >= 0.0717 && r.nees_pos[i] <= 12.84) ++in;
  }
  PositionConsistency c;
  if (cnt == 0) return c;
  c.nees_mean = sum / cnt;
  c.inside_99 = static_cast<double>(in) / cnt;
  c.error_rms_m = std::sqrt(sq / cnt);
  return c;
}

double ValueAt(const DriveRun& r, const std::vector<double>& v, double t) {
  for (size_t i = 0; i < v.size(); ++i)
    if (r.t[i] >= t - 1e-6) return v[i];
  return v.back();
}

Truth AnalyticDrive() {
  return [](double t) { return SyntheticDrive(kG).At(t); };
}

// Stands (yaw 30 deg, slightly tilted) until t_start, then accelerates along its x axis at 1 m/s^2
// for 10 s and keeps the speed.
Truth StandThenGo(double t_start) {
  return [t_start](double t) {
    TruthState s;
    s.R = FromRollPitchYaw(0.01, -0.02, 30.0 * M_PI / 180.0);
    const Eigen::Vector3d fwd = s.R.col(0);
    const double tm = std::max(0.0, t - t_start), ta = std::min(tm, 10.0);
    const double dist = 0.5 * ta * ta + 10.0 * (tm - ta);
    s.p = Eigen::Vector3d(5.0, -3.0, 0.0) + dist * fwd;
    s.v = std::min(tm, 10.0) * fwd;
    s.a = (tm > 0.0 && tm < 10.0 ? 1.0 : 0.0) * fwd;
    s.w_body.setZero();
    s.f_body = s.R.transpose() * (s.a + Eigen::Vector3d(0.0, 0.0, kG));
    return s;
  };
}

// A flat circle at 10 m/s (radius 100 m): the body never slides sideways or moves vertically.
Truth Circle() {
  return [](double t) {
    constexpr double kR = 100.0, kW = 0.1;
    TruthState s;
    const double th = kW * t;
    s.p = Eigen::Vector3d(kR * std::sin(th), kR * (1.0 - std::cos(th)), 0.0);
    s.v = Eigen::Vector3d(kR * kW * std::cos(th), kR * kW * std::sin(th), 0.0);
    s.a = Eigen::Vector3d(-kR * kW * kW * std::sin(th), kR * kW * kW * std::cos(th), 0.0);
    s.R = FromRollPitchYaw(0.0, 0.0, th);
    s.w_body = Eigen::Vector3d(0.0, 0.0, kW);
    s.f_body = s.R.transpose() * (s.a + Eigen::Vector3d(0.0, 0.0, kG));
    return s;
  };
}

// The same circle driven sideways (the body turned 90 deg: its y axis along the motion), as a
// vehicle that is not a car, or the OXTS motion of a drive whose records are broken (the sweep's
// 2011_09_26_drive_0093: 10 m/s sideways and 6 m/s down). The non-holonomic constraint does not
// hold.
Truth SidewaysCircle() {
  return [](double t) {
    TruthState s = Circle()(t);
    s.R = FromRollPitchYaw(0.0, 0.0, 0.1 * t - M_PI / 2.0);
    s.f_body = s.R.transpose() * (s.a + Eigen::Vector3d(0.0, 0.0, kG));
    return s;
  };
}

ReceiverState Fixed() { return ReceiverState{true, GnssFixType::kRtkFixed, 0.02, 0.03}; }
ReceiverState Float() { return ReceiverState{true, GnssFixType::kRtkFloat, 0.25, 0.4}; }
ReceiverState Single() { return ReceiverState{true, GnssFixType::kSingle, 1.5, 2.5}; }
ReceiverState None() { return ReceiverState{false}; }

TEST(InsFilterModelsTest, FloatBiasStepDoesNotLeakIntoTiltOrTheOutage) {
  // RTK fixed for 40 s, then float (a new, correlated bias) for 50 s, then a 30 s outage.
  const Receiver rx = [](double t) { return t < 40.0 ? Fixed() : t < 90.0 ? Float() : None(); };
  double tilt_before[2], tilt[2], outage[2];
  for (int model = 0; model < 2; ++model) {
    InsFilter::Options o = BaseOptions();
    if (model == 0) o.gnss_error_rtk_float.correlated_fraction = 0.0;  // white (the old model)
    InsFilter f = InsFilter::Create(o).value();
    const DriveRun r = RunModelDrive(AnalyticDrive(), 120.0, rx, ErrorProcess(), &f, 11);
    tilt_before[model] = MaxIn(r, r.tilt_deg, 25.0, 40.0);
    tilt[model] = MaxIn(r, r.tilt_deg, 40.0, 55.0);
    outage[model] = MaxIn(r, r.pos_err, 90.0, 121.0);
  }
  std::printf(
      "fixed -> float at 40 s, outage 90-120 s: max tilt error 25-40 s (fixed) %.4f deg; 40-55 s "
      "(after the step) float white %.4f deg, Gauss-Markov %.4f deg; max position error in the "
      "outage white %.3f m, Gauss-Markov %.3f m\n",
      tilt_before[1], tilt[0], tilt[1], outage[0], outage[1]);
  EXPECT_LT(tilt[1], 0.5 * tilt[0]);
  EXPECT_LT(tilt[1], 1.5 * tilt_before[1]);  // no more tilt than under RTK fixed
  EXPECT_LT(outage[1], 0.5 * outage[0]);
}

TEST(InsFilterModelsTest, PositionCovarianceIsConsistentUnderCorrelatedFloatErrors) {
  const Receiver rx = [](double) { return Float(); };
  double inside[2], mean[2];
  for (int model = 0; model < 2; ++model) {
    InsFilter::Options o = BaseOptions();
    if (model == 0) o.gnss_error_rtk_float.correlated_fraction = 0.0;
    InsFilter f = InsFilter::Create(o).value();
    const DriveRun r = RunModelDrive(AnalyticDrive(), 300.0, rx, ErrorProcess(), &f, 5);
    const PositionConsistency c = PositionConsistencyFrom(r, 20.0);
    inside[model] = c.inside_99;
    mean[model] = c.nees_mean;
  }
  std::printf(
      "float fixes 300 s (90 %% of the variance a 30 s Gauss-Markov bias): position NEES (3 dof) "
      "white model mean %.2f, %.1f %% inside the 99 %% bounds; Gauss-Markov model mean %.2f, "
      "%.1f %% inside\n",
      mean[0], 100.0 * inside[0], mean[1], 100.0 * inside[1]);
  EXPECT_GE(inside[1], 0.9);
  EXPECT_LT(mean[1], 6.0);
  EXPECT_LT(inside[0], inside[1]);  // the white model is overconfident
}

TEST(InsFilterModelsTest, CorrelatedFixedErrorModelIsConsistentWhereTheWhiteOneIsNot) {
  // RTK fixed for 300 s. The receiver's fixed errors are white, or (multipath, residual
  // atmosphere, a blended output converging) 90 % a 30 s Gauss-Markov bias; the filter models
  // them as white (the default) or as the float class by default (90 %, 30 s:
  // scripts/experiments/rtk_fixed_correlated.yaml).
  EXPECT_DOUBLE_EQ(InsFilter::Options().gnss_error_rtk_fixed.correlated_fraction, 0.0);
  const Receiver rx = [](double) { return Fixed(); };
  double mean[2][2], inside[2][2], rms[2][2];
  for (int truth = 0; truth < 2; ++truth) {
    for (int model = 0; model < 2; ++model) {
      ErrorProcess ep;
      if (truth == 1) ep.rho_fixed = 0.9;
      InsFilter::Options o = BaseOptions();
      if (model == 1) o.gnss_error_rtk_fixed = {0.9, 30.0};
      InsFilter f = InsFilter::Create(o).value();
      const DriveRun r = RunModelDrive(AnalyticDrive(), 300.0, rx, ep, &f, 17);
      const PositionConsistency c = PositionConsistencyFrom(r, 20.0);
      mean[truth][model] = c.nees_mean;
      inside[truth][model] = c.inside_99;
      rms[truth][model] = c.error_rms_m;
    }
  }
  std::printf(
      "RTK fixed 300 s, position NEES mean / share inside the 99 %% bounds / error RMS:\n"
      "  white errors:      white model %.2f / %.1f %% / %.4f m, "
      "correlated %.2f / %.1f %% / %.4f m\n"
      "  correlated errors: white model %.2f / %.1f %% / %.4f m, "
      "correlated %.2f / %.1f %% / %.4f m\n",
      mean[0][0], 100.0 * inside[0][0], rms[0][0], mean[0][1], 100.0 * inside[0][1], rms[0][1],
      mean[1][0], 100.0 * inside[1][0], rms[1][0], mean[1][1], 100.0 * inside[1][1], rms[1][1]);
  // Correlated errors: the correlated model is consistent, the white one overconfident.
  EXPECT_GE(inside[1][1], 0.9);
  EXPECT_LT(mean[1][1], 6.0);
  EXPECT_GT(mean[1][0], 2.0 * mean[1][1]);
  EXPECT_LT(inside[1][0], inside[1][1]);
  // White errors: the correlated model errs on the safe side (not overconfident) and its
  // position stays at the fixes' accuracy (2 cm horizontal, 3 cm vertical).
  EXPECT_LT(mean[0][1], 3.0);
  EXPECT_LT(rms[0][1], 0.04);
}

TEST(InsFilterModelsTest, ZeroVelocityUpdatesHoldAStandingVehicleAndRelease) {
  // Single-point GNSS while standing for 20 s, RTK fixed once moving.
  const Receiver rx = [](double t) { return t < 20.0 ? Single() : Fixed(); };
  double yaw_drift[2], speed[2], speed_after[2];
  int zupts[2], zupts_total[2];
  for (int zupt = 0; zupt < 2; ++zupt) {
    InsFilter::Options o = BaseOptions();
    o.zupt = zupt == 1;
    InsFilter f = InsFilter::Create(o).value();
    const DriveRun r = RunModelDrive(StandThenGo(20.0), 40.0, rx, ErrorProcess(), &f, 3);
    yaw_drift[zupt] = std::abs(ValueAt(r, r.yaw_deg, 19.0) - ValueAt(r, r.yaw_deg, 2.0));
    // The detector engages once the tilt and accelerometer bias have settled (~2 s here).
    speed[zupt] = MaxIn(r, r.speed_err, 5.0, 20.0);
    speed_after[zupt] = MaxIn(r, r.speed_err, 22.0, 41.0);
    zupts[zupt] = r.zupts_at_20s;
    zupts_total[zupt] = f.num_zero_velocity_updates();
  }
  std::printf(
      "standing 20 s on single-point GNSS, then 1 m/s^2: ZUPT off / on: yaw drift 2-19 s %.4f / "
      "%.4f deg, max speed error standing 5-20 s %.4f / %.4f m/s, moving %.4f / %.4f m/s; ZUPTs %d "
      "/ %d "
      "(after the start %d)\n",
      yaw_drift[0], yaw_drift[1], speed[0], speed[1], speed_after[0], speed_after[1], zupts[0],
      zupts[1], zupts_total[1] - zupts[1]);
  EXPECT_EQ(zupts_total[0], 0);
  EXPECT_GT(zupts[1], 150);                 // ~10 Hz while standing
  EXPECT_EQ(zupts_total[1] - zupts[1], 0);  // none once moving
  EXPECT_LT(speed[1], 0.02);
  EXPECT_LT(speed[1], 0.5 * speed[0]);
  EXPECT_LT(yaw_drift[1], 0.5 * yaw_drift[0]);
  EXPECT_LT(speed_after[1], 0.05);  // released: the start is not held back
}

TEST(InsFilterModelsTest, NonHolonomicConstraintBoundsTheOutageDrift) {
  const Receiver rx = [](double t) { return t < 30.0 ? Fixed() : None(); };
  double outage[2];
  for (int nhc = 0; nhc < 2; ++nhc) {
    InsFilter::Options o = BaseOptions();
    o.nhc_sigma_mps = nhc == 1 ? 0.05 : 0.0;
    InsFilter f = InsFilter::Create(o).value();
    const DriveRun r = RunModelDrive(Circle(), 60.0, rx, ErrorProcess(), &f, 9);
    outage[nhc] = MaxIn(r, r.pos_err, 30.0, 61.0);
  }
  std::printf("circle at 10 m/s, outage 30-60 s: max position error NHC off %.3f m, on %.3f m\n",
              outage[0], outage[1]);
  EXPECT_LT(outage[1], 0.5 * outage[0]);
}

// Where the vehicle does not keep to its x axis, the constraint's innovation test refuses it, so
// the filter is as good as without it (without the test it pulled the velocity sideways against
// the GNSS: 68 m of error on the sweep's drive 0093).
TEST(InsFilterModelsTest, NonHolonomicConstraintRefusedWhereItDoesNotHold) {
  const Receiver rx = [](double t) { return t < 30.0 ? Fixed() : None(); };
  double worst[2], outage[2];
  for (int nhc = 0; nhc < 2; ++nhc) {
    InsFilter::Options o = BaseOptions();
    o.nhc_sigma_mps = nhc == 1 ? 0.1 : 0.0;
    InsFilter f = InsFilter::Create(o).value();
    const DriveRun r = RunModelDrive(SidewaysCircle(), 40.0, rx, ErrorProcess(), &f, 9);
    worst[nhc] = MaxIn(r, r.pos_err, 0.0, 30.0);
    outage[nhc] = MaxIn(r, r.pos_err, 30.0, 41.0);
  }
  std::printf(
      "sideways circle: max position error with GNSS NHC off %.3f m, on %.3f m; in the "
      "10 s outage %.3f / %.3f m\n",
      worst[0], worst[1], outage[0], outage[1]);
  EXPECT_LT(worst[1], 0.2);
  EXPECT_LT(outage[1], 1.2 * outage[0] + 0.05);
}

// An RT3003-like datasheet, as slam_mms_sim simulates it.
ImuNoiseSpec TacticalImu() {
  ImuNoiseSpec tactical;
  tactical.gyro_noise_density = 5.8e-5;
  tactical.accel_noise_density = 5.0e-4;
  tactical.gyro_bias_instability = 9.7e-6;
  tactical.gyro_bias_correlation_time_s = 300.0;
  tactical.accel_bias_instability = 1.0e-4;
  tactical.accel_bias_correlation_time_s = 300.0;
  tactical.gyro_turn_on_bias_sigma = 2.4e-5;
  tactical.accel_turn_on_bias_sigma = 5.0e-4;
  return tactical;
}

// A car along the analytic drive's path (S-curves at 8-12 m/s over a hill): its x axis along the
// velocity, no roll, and an IMU mounted off its axes, R_body_vehicle = Exp((0, pitch, yaw)).
// Body rates by central differences of the attitude (exact to ~1e-9 rad/s).
Truth MisalignedCar(double pitch_rad, double yaw_rad) {
  const Eigen::Matrix3d R_body_vehicle = so3::Exp(Eigen::Vector3d(0.0, pitch_rad, yaw_rad));
  const auto vehicle = [](double t) {
    const Eigen::Vector3d v = SyntheticDrive(kG).At(t).v;
    return FromRollPitchYaw(0.0, -std::asin(v.z() / v.norm()), std::atan2(v.y(), v.x()));
  };
  return [=](double t) {
    TruthState s = SyntheticDrive(kG).At(t);
    constexpr double kH = 1e-4;
    s.R = vehicle(t) * R_body_vehicle.transpose();
    const Eigen::Matrix3d Rm = vehicle(t - kH) * R_body_vehicle.transpose();
    const Eigen::Matrix3d Rp = vehicle(t + kH) * R_body_vehicle.transpose();
    s.w_body = so3::Log(Rm.transpose() * Rp) / (2.0 * kH);
    s.f_body = s.R.transpose() * (s.a + Eigen::Vector3d(0.0, 0.0, kG));
    return s;
  };
}

// An IMU mounted 0.4 deg (yaw) and -0.3 deg (pitch) off the car's axes, as KITTI's OXTS sits off
// its car's travel direction (docs/ins.md), with the tactical IMU's stated noise: the constraint
// that takes the IMU's axes for the car's turns the heading onto the travel direction against
// the RTK track; with the misalignment in the state it finds the angles and keeps the heading,
// also through the outage.
TEST(InsFilterModelsTest, NonHolonomicConstraintEstimatesTheImuMisalignment) {
  const double kPitch = -0.3 * M_PI / 180.0, kYaw = 0.4 * M_PI / 180.0;
  const ImuNoiseSpec imu = TacticalImu();
  const Receiver rx = [](double t) { return t < 90.0 ? Fixed() : None(); };
  // NHC off; on, the IMU's axes taken as the car's; on, the misalignment estimated; on, the
  // calibrated mounting given as exact. Means over seeds.
  constexpr int kCases = 4, kSeeds = 4;
  double yaw_rms[kCases] = {}, outage[kCases] = {};
  // The settled estimate is logged once per filter that estimates it.
  int logged = 0;
  const LogLevel previous_level = MinLogLevel();
  SetMinLogLevel(LogLevel::kInfo);
  const LogSink previous_sink = SetLogSink([&](LogLevel, const std::string& m) {
    if (m.find("IMU-to-vehicle misalignment pitch") != std::string::npos) ++logged;
  });
  for (uint32_t seed = 1; seed <= kSeeds; ++seed) {
    for (int c = 0; c < kCases; ++c) {
      InsFilter::Options o = BaseOptions();
      o.SetImuNoise(imu);
      o.nhc_sigma_mps = c == 0 ? 0.0 : 0.05;
      // This car's only constraint error is the mounting: the constraint taken as white (the
      // defaults' correlation times weaken it, and with it what an unmodelled mounting costs).
      o.nhc_lateral_correlation_time_s = o.nhc_vertical_correlation_time_s = 0.0;
      o.vehicle_misalignment_sigma_rad = c == 2 ? 0.0175 : 0.0;
      if (c == 3) {
        o.vehicle_pitch_misalignment_rad = kPitch;
        o.vehicle_yaw_misalignment_rad = kYaw;
      }
      InsFilter f = InsFilter::Create(o).value();
      const DriveRun r =
          RunModelDrive(MisalignedCar(kPitch, kYaw), 120.0, rx, ErrorProcess(), &f, seed, &imu);
      yaw_rms[c] += RmsIn(r, r.yaw_deg, 30.0, 90.0) / kSeeds;
      outage[c] += MaxIn(r, r.pos_err, 90.0, 121.0) / kSeeds;
      const Eigen::Vector2d m = f.vehicle_misalignment_rad() * 180.0 / M_PI;
      if (c == 2) {
        const Eigen::Vector2d sigma =
            f.covariance().block<2, 2>(18, 18).diagonal().cwiseSqrt() * 180.0 / M_PI;
        std::printf("seed %u: misalignment estimate pitch %.3f +- %.3f, yaw %.3f +- %.3f deg\n",
                    seed, m.x(), sigma.x(), m.y(), sigma.y());
        // Found within three of their own sigmas, and the sigmas well below the prior's 1 deg.
        EXPECT_NEAR(m.x(), -0.3, 3.0 * sigma.x());
        EXPECT_NEAR(m.y(), 0.4, 3.0 * sigma.y());
        EXPECT_LT(sigma.maxCoeff(), 0.1);
      }
      if (c == 3) {
        EXPECT_EQ(m, Eigen::Vector2d(-0.3, 0.4));
      }
    }
  }
  SetLogSink(previous_sink);
  SetMinLogLevel(previous_level);
  EXPECT_EQ(logged, kSeeds);
  std::printf(
      "IMU mounted pitch -0.3 / yaw 0.4 deg off a car, %d seeds: yaw error RMS with RTK (30-90 s) "
      "NHC off %.3f, on as if aligned %.3f, on estimating %.3f, on calibrated %.3f deg; max error "
      "in the 30 s outage %.3f / %.3f / %.3f / %.3f m\n",
      kSeeds, yaw_rms[0], yaw_rms[1], yaw_rms[2], yaw_rms[3], outage[0], outage[1], outage[2],
      outage[3]);
  // Taken as aligned, the heading follows the travel direction (0.4 deg off); estimated, it
  // stays within a few hundredths of a degree.
  EXPECT_GT(yaw_rms[1], 0.3);
  EXPECT_LT(yaw_rms[2], 0.25 * yaw_rms[1]);
  EXPECT_LT(yaw_rms[3], 0.25 * yaw_rms[1]);
  // The constraint bounds the outage, with the angles better than without them and than without
  // the constraint.
  EXPECT_LT(outage[2], 0.5 * outage[1]);
  EXPECT_LT(outage[2], outage[0]);
}

// A car along the analytic drive's path whose rear axle (its non-holonomic point) follows the
// path, its tyres slipping by `sideslip` rad per m/s^2 of lateral acceleration (the axle's
// velocity that much to the left of the car's x axis; a real car's is to the right, into the turn
// goes its nose: negative), no roll, and an IMU aligned with the car `lever_m` ahead of the axle.
// Everything at the IMU by central differences.
Truth CarWithLeverArm(double lever_m, double sideslip) {
  const auto car = [=](double t, Eigen::Vector3d* p_imu) {
    const TruthState a = SyntheticDrive(kG).At(t);
    const Eigen::Vector2d vh = a.v.head<2>();
    const double a_lat = (vh.x() * a.a.y() - vh.y() * a.a.x()) / vh.norm();
    const double yaw = std::atan2(vh.y(), vh.x()) - sideslip * a_lat;
    const Eigen::Matrix3d R = FromRollPitchYaw(0.0, -std::asin(a.v.z() / a.v.norm()), yaw);
    *p_imu = a.p + R * Eigen::Vector3d(lever_m, 0.0, 0.0);
    return R;
  };
  return [=](double t) {
    constexpr double kH = 1e-3;
    Eigen::Vector3d pm, p0, pp;
    const Eigen::Matrix3d Rm = car(t - kH, &pm), R = car(t, &p0), Rp = car(t + kH, &pp);
    TruthState s;
    s.p = p0;
    s.v = (pp - pm) / (2.0 * kH);
    s.a = (pp - 2.0 * p0 + pm) / (kH * kH);
    s.R = R;
    s.w_body = so3::Log(Rm.transpose() * Rp) / (2.0 * kH);
    s.f_body = R.transpose() * (s.a + Eigen::Vector3d(0.0, 0.0, kG));
    return s;
  };
}

// An IMU 1.5 m ahead of the rear axle, tyres slipping 0.003 rad per m/s^2 (1.7 deg/g), the
// tactical IMU's stated noise: at the IMU the car moves sideways by lever * yaw rate + sideslip *
// speed * lateral acceleration (up to 0.3 m/s here). The constraint that takes the IMU's
// velocity for the axle's turns the heading into the turns; with the lateral model in the state
// it finds the lever arm and keeps the heading, also through the outage.
TEST(InsFilterModelsTest, NonHolonomicConstraintEstimatesTheLeverArmToTheRearAxle) {
  constexpr double kLever = 1.5, kSlip = -0.003;
  const ImuNoiseSpec imu = TacticalImu();
  const Receiver rx = [](double t) { return t < 90.0 ? Fixed() : None(); };
  // NHC off; on, the IMU taken as at the axle without slip; on, the lateral model estimated
  // (the defaults); on, the true model given as exact.
  constexpr int kCases = 4, kSeeds = 3;
  double yaw_rms[kCases] = {}, outage[kCases] = {};
  for (uint32_t seed = 1; seed <= kSeeds; ++seed) {
    for (int c = 0; c < kCases; ++c) {
      InsFilter::Options o = BaseOptions();
      o.SetImuNoise(imu);
      o.nhc_sigma_mps = c == 0 ? 0.0 : 0.05;
      // This car's only constraint error is its lateral model: the constraint taken as white.
      o.nhc_lateral_correlation_time_s = o.nhc_vertical_correlation_time_s = 0.0;
      o.vehicle_misalignment_sigma_rad = 0.0;
      if (c != 2) o.vehicle_lever_arm_sigma_m = o.vehicle_sideslip_sigma_rad_per_mps2 = 0.0;
      if (c == 3) {
        o.vehicle_lever_arm_m = kLever;
        o.vehicle_sideslip_rad_per_mps2 = kSlip;
      }
      InsFilter f = InsFilter::Create(o).value();
      const DriveRun r =
          RunModelDrive(CarWithLeverArm(kLever, kSlip), 120.0, rx, ErrorProcess(), &f, seed, &imu);
      yaw_rms[c] += RmsIn(r, r.yaw_deg, 30.0, 90.0) / kSeeds;
      outage[c] += MaxIn(r, r.pos_err, 90.0, 121.0) / kSeeds;
      const Eigen::Vector2d l = f.vehicle_lateral_model();
      if (c == 2) {
        const Eigen::Vector2d sigma = f.covariance().block<2, 2>(20, 20).diagonal().cwiseSqrt();
        std::printf("seed %u: lever arm %.3f +- %.3f m, sideslip %.5f +- %.5f rad/(m/s^2)\n", seed,
                    l.x(), sigma.x(), l.y(), sigma.y());
        EXPECT_NEAR(l.x(), kLever, 3.0 * sigma.x());
        EXPECT_NEAR(l.y(), kSlip, 3.0 * sigma.y());
        EXPECT_LT(sigma.x(), 0.25);  // from the prior's 1 m
      }
      if (c == 3) {
        EXPECT_EQ(l, Eigen::Vector2d(kLever, kSlip));
      }
    }
  }
  std::printf(
      "IMU 1.5 m ahead of the rear axle, sideslip -0.003 rad/(m/s^2), %d seeds: yaw error RMS with "
      "RTK (30-90 s) NHC off %.3f, on without the model %.3f, on estimating it %.3f, on with it "
      "given %.3f deg; max error in the 30 s outage %.3f / %.3f / %.3f / %.3f m\n",
      kSeeds, yaw_rms[0], yaw_rms[1], yaw_rms[2], yaw_rms[3], outage[0], outage[1], outage[2],
      outage[3]);
  EXPECT_LT(yaw_rms[2], 0.5 * yaw_rms[1]);
  EXPECT_LT(yaw_rms[3], 0.5 * yaw_rms[1]);
  EXPECT_LT(outage[2], outage[1]);
  EXPECT_LT(outage[2], outage[0]);
}

// A car along the analytic drive's path whose body pitches about its velocity as a car does on
// its suspension and over the road (braking, bumps, grade changes): pitch(t) a smooth random
// process of 0.3 deg standard deviation correlated over a second (a sum of sinusoids of random
// phase and frequency below 0.25 Hz: a flat spectrum to B = 0.25 Hz, whose integral time
// 1 / (4 B) is 1 s), so at 8-12 m/s its velocity along its own z axis wanders by about 0.05 m/s,
// as KITTI's records do (docs/ins.md). The IMU is aligned with the body.
Truth PitchingCar(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  constexpr int kTerms = 24;
  std::vector<std::pair<double, double>> terms;  // (angular frequency, phase)
  for (int i = 0; i < kTerms; ++i)
    terms.emplace_back(2.0 * M_PI * 0.25 * u01(rng), 2.0 * M_PI * u01(rng));
  const double amplitude = 0.3 * M_PI / 180.0 * std::sqrt(2.0 / kTerms);
  const auto body = [=](double t) {
    const Eigen::Vector3d v = SyntheticDrive(kG).At(t).v;
    double pitch = 0.0;
    for (const auto& [w, phase] : terms) pitch += amplitude * std::sin(w * t + phase);
    return FromRollPitchYaw(0.0, -std::asin(v.z() / v.norm()) + pitch, std::atan2(v.y(), v.x()));
  };
  return [=](double t) {
    TruthState s = SyntheticDrive(kG).At(t);
    constexpr double kH = 1e-4;
    s.R = body(t);
    s.w_body = so3::Log(body(t - kH).transpose() * body(t + kH)) / (2.0 * kH);
    s.f_body = s.R.transpose() * (s.a + Eigen::Vector3d(0.0, 0.0, kG));
    return s;
  };
}

// The constraint's error on that car is not white: taken as white at 10 Hz, its vertical row
// holds the velocity's z to the wandering pitch 30x more firmly than it deserves, and the height
// in an outage follows the wander; with the error's correlation time the filter weighs it as what
// it is, and its position covariance stays honest.
TEST(InsFilterModelsTest, CorrelatedConstraintErrorsAreNotTakenAsWhite) {
  const ImuNoiseSpec imu = TacticalImu();
  const Receiver rx = [](double t) { return t < 60.0 ? Fixed() : None(); };
  // NHC off; on, white; on, correlated over 1 s. Means over seeds.
  constexpr int kCases = 3, kSeeds = 4;
  double up[kCases] = {}, nees[kCases] = {}, outage[kCases] = {};
  for (uint32_t seed = 1; seed <= kSeeds; ++seed) {
    for (int c = 0; c < kCases; ++c) {
      InsFilter::Options o = BaseOptions();
      o.SetImuNoise(imu);
      o.nhc_sigma_mps = c == 0 ? 0.0 : 0.05;
      o.nhc_lateral_correlation_time_s = 0.0;  // only the vertical row is examined
      o.nhc_vertical_correlation_time_s = c == 2 ? 1.0 : 0.0;
      o.vehicle_misalignment_sigma_rad = 0.0;
      o.vehicle_lever_arm_sigma_m = o.vehicle_sideslip_sigma_rad_per_mps2 = 0.0;
      InsFilter f = InsFilter::Create(o).value();
      const DriveRun r =
          RunModelDrive(PitchingCar(seed), 120.0, rx, ErrorProcess(), &f, seed, &imu);
      up[c] += MaxIn(r, r.up_err, 60.0, 121.0) / kSeeds;
      outage[c] += MaxIn(r, r.pos_err, 60.0, 121.0) / kSeeds;
      // The outage's epochs after its start (one a second).
      nees[c] += MeanIn(r, r.nees_pos, 61.0, 121.0) / kSeeds;
    }
  }
  std::printf(
      "car pitching 0.3 deg (~1 s) on its suspension, %d seeds, 60 s outage: max height error "
      "NHC off %.3f, white %.3f, correlated %.3f m; max position error %.3f / %.3f / %.3f m; mean "
      "position NEES (3 dof) %.1f / %.1f / %.1f\n",
      kSeeds, up[0], up[1], up[2], outage[0], outage[1], outage[2], nees[0], nees[1], nees[2]);
  // Correlated: the height better than as white and the covariance consistent (NEES of 3 dof
  // within a factor of 3); as white, over-confident.
  EXPECT_LT(up[2], up[1]);
  EXPECT_LT(nees[2], 9.0);
  EXPECT_GT(nees[1], nees[2]);
  // The constraint still bounds the outage.
  EXPECT_LT(outage[2], outage[0]);
}

// A tactical IMU (RT3003-like datasheet, as slam_mms_sim simulates it) under RTK fixed GNSS, then
// a 60 s outage: the filter modelled with the IMU's stated noise (SetImuNoise) against its
// defaults (an IMU of unknown grade, 3-25x noisier). The stated model learns the biases and the
// attitude from the GNSS and keeps them through the outage; its position covariance stays
// consistent.
TEST(InsFilterModelsTest, StatedImuNoiseBoundsTheOutageDrift) {
  const ImuNoiseSpec tactical = TacticalImu();
  ASSERT_TRUE(tactical.Validate().ok());
  const Receiver rx = [](double t) { return t < 90.0 ? Fixed() : t < 150.0 ? None() : Fixed(); };
  double outage[2] = {0.0, 0.0}, nees_in[2] = {0.0, 0.0};
  const int kSeeds = 4;
  for (uint32_t seed = 1; seed <= kSeeds; ++seed) {
    for (int model = 0; model < 2; ++model) {
      InsFilter::Options o = BaseOptions();
      if (model == 1) o.SetImuNoise(tactical);
      InsFilter f = InsFilter::Create(o).value();
      const DriveRun r =
          RunModelDrive(AnalyticDrive(), 150.0, rx, ErrorProcess(), &f, seed, &tactical);
      const double max_err = MaxIn(r, r.pos_err, 90.0, 151.0);
      // The outage's epochs after its start (one a second).
      const double mean_nees = MeanIn(r, r.nees_pos, 91.0, 151.0);
      std::printf("seed %u, %s: max position error in the outage %.3f m, mean NEES %.2f\n", seed,
                  model == 0 ? "defaults" : "stated noise", max_err, mean_nees);
      outage[model] += max_err / kSeeds;
      nees_in[model] += mean_nees / kSeeds;
    }
  }
  std::printf(
      "tactical IMU, 60 s outage after 90 s of RTK fixed, mean of %d seeds: filter defaults / "
      "stated noise: max position error in the outage %.3f / %.3f m, mean position NEES in the "
      "outage %.2f / %.2f (3 dof)\n",
      kSeeds, outage[0], outage[1], nees_in[0], nees_in[1]);
  EXPECT_LT(outage[1], 0.8 * outage[0]);
  // The defaults' covariance is several times too wide (NEES well below 3); the stated model's is
  // consistent: its mean within the 95 % chi-square bounds of one 3-dof epoch.
  EXPECT_LT(nees_in[0], 1.0);
  EXPECT_GT(nees_in[1], 0.22);
  EXPECT_LT(nees_in[1], 9.35);
}

TEST(InsFilterModelsTest, SetImuNoiseFillsBothNoiseModels) {
  ImuNoiseSpec s;
  s.gyro_noise_density = 1e-4;
  s.accel_noise_density = 1e-3;
  s.gyro_bias_instability = 2e-5;
  s.gyro_bias_correlation_time_s = 200.0;
  s.accel_bias_instability = 3e-4;
  s.accel_bias_correlation_time_s = 800.0;
  s.gyro_turn_on_bias_sigma = 0.0;  // not stated: the instability alone
  s.accel_turn_on_bias_sigma = 4e-4;
  InsFilter::Options o;
  o.SetImuNoise(s);
  EXPECT_EQ(o.gyro_noise_density, 1e-4);
  EXPECT_EQ(o.accel_noise_density, 1e-3);
  EXPECT_DOUBLE_EQ(o.gyro_bias_random_walk, 2e-5 * std::sqrt(2.0 / 200.0));
  EXPECT_DOUBLE_EQ(o.accel_bias_random_walk, 3e-4 * std::sqrt(2.0 / 800.0));
  EXPECT_DOUBLE_EQ(o.init_sigma_gyro_bias_radps, 2e-5);
  EXPECT_DOUBLE_EQ(o.init_sigma_accel_bias_mps2, 5e-4);
  EXPECT_TRUE(o.Validate().ok());
  ImuPreintegration::Options p;
  p.SetImuNoise(s);
  EXPECT_EQ(p.gyro_noise_density, o.gyro_noise_density);
  EXPECT_EQ(p.accel_bias_random_walk, o.accel_bias_random_walk);
  s.gyro_bias_correlation_time_s = 0.0;
  EXPECT_EQ(s.Validate().ToString(),
            "INVALID_ARGUMENT: ImuNoiseSpec::gyro_bias_correlation_time_s = 0; must be > 0 [s]");
}

TEST(InsFilterModelsTest, ModelOptionsAreValidated) {
  InsFilter::Options o;
  o.gnss_error_rtk_float.correlated_fraction = 1.0;
  Status s = InsFilter::Create(o).status();
  EXPECT_NE(s.message().find("gnss_error_rtk_float.correlated_fraction"), std::string::npos)
      << s.message();
  o = InsFilter::Options();
  o.gnss_error_code.correlation_time_s = 0.0;
  s = InsFilter::Create(o).status();
  EXPECT_NE(s.message().find("gnss_error_code.correlation_time_s"), std::string::npos);
  o = InsFilter::Options();
  o.zupt_max_speed_mps = -1.0;
  EXPECT_FALSE(InsFilter::Create(o).ok());
  o = InsFilter::Options();
  o.nhc_sigma_mps = std::nan("");
  EXPECT_FALSE(InsFilter::Create(o).ok());
  o = InsFilter::Options();
  o.vehicle_yaw_misalignment_rad = 0.5;
  s = InsFilter::Create(o).status();
  EXPECT_NE(s.message().find("vehicle_yaw_misalignment_rad"), std::string::npos) << s.message();
  o = InsFilter::Options();
  o.vehicle_misalignment_sigma_rad = -0.01;
  s = InsFilter::Create(o).status();
  EXPECT_NE(s.message().find("vehicle_misalignment_sigma_rad"), std::string::npos) << s.message();
  // The lateral model: each field named.
  const auto named = [](void (*set)(InsFilter::Options*), const char* field) {
    InsFilter::Options bad;
    set(&bad);
    const Status st = InsFilter::Create(bad).status();
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_NE(st.message().find(field), std::string::npos) << st.message();
  };
  named([](InsFilter::Options* b) { b->vehicle_lever_arm_m = 12.0; }, "vehicle_lever_arm_m");
  named([](InsFilter::Options* b) { b->vehicle_lever_arm_sigma_m = -1.0; },
        "vehicle_lever_arm_sigma_m");
  named([](InsFilter::Options* b) { b->vehicle_sideslip_rad_per_mps2 = std::nan(""); },
        "vehicle_sideslip_rad_per_mps2");
  named([](InsFilter::Options* b) { b->vehicle_sideslip_sigma_rad_per_mps2 = 0.1; },
        "vehicle_sideslip_sigma_rad_per_mps2");
  named([](InsFilter::Options* b) { b->nhc_lateral_correlation_time_s = -1.0; },
        "nhc_lateral_correlation_time_s");
  named([](InsFilter::Options* b) { b->nhc_vertical_correlation_time_s = std::nan(""); },
        "nhc_vertical_correlation_time_s");
}

}  // namespace
}  // namespace slam_mms
