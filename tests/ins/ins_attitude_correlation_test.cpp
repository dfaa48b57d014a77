// InsFilter::MarkAttitudeEpoch / AttitudeSinceEpoch: the filter's cross-covariance between the
// attitude errors of two times (level 2's POS attitude chain). Monte Carlo over noisy drives: the
// sample correlation of the true attitude errors at the two times matches the filter's, per axis
// (a cross-covariance propagated without the updates' (I - K H) would stay at the epoch's
// covariance, a correlation of 1); right after the mark it is the covariance itself; a new
// initialisation forgets the epoch; an external POS has none.
#include <gtest/gtest.h>

#include <cmath>

#include "ins/synthetic_drive.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/ins/ins_filter.hpp"

namespace slam_mms {
namespace {

using testing::SyntheticDrive;
using testing::TruthState;

using testing::kOrigin;
using testing::kT0;

struct Sample {
  Eigen::Vector3d e_epoch, e_now;  // true attitude errors (right perturbation, body)
  InsFilter::AttitudeCorrelation c;
};

// One noisy drive (testing::MakeNoisyDrive: the IMU at the filter's stated noise, 2 cm / 3 cm
// GNSS at 10 Hz, the initial state drawn from the filter's initial sigmas); the epoch marked at
// `epoch_s`, read at `now_s`.
Sample RunNoisyDrive(uint32_t seed, double epoch_s, double now_s) {
  InsFilter::Options o;
  o.gravity_mps2 = SyntheticDrive().gravity();
  o.gnss.t_body_antenna = Eigen::Vector3d(0.5, 0.2, 1.2);
  o.init_sigma_position_m = 0.5;
  o.init_sigma_yaw_rad = 0.5 * M_PI / 180.0;
  testing::NoisyDriveSigmas sig;
  sig.roll_pitch_rad = o.init_sigma_roll_pitch_rad;
  sig.yaw_rad = o.init_sigma_yaw_rad;
  sig.position_m = o.init_sigma_position_m;
  sig.velocity_mps = o.init_sigma_velocity_mps;
  sig.accel_bias_mps2 = o.init_sigma_accel_bias_mps2;
  sig.gyro_bias_radps = o.init_sigma_gyro_bias_radps;
  const testing::NoisyDrive d = testing::MakeNoisyDrive(o, now_s, seed, kT0, kOrigin, sig);
  auto f = InsFilter::Create(o);
  EXPECT_TRUE(f.ok());
  InsFilter& filter = *f;
  filter.mutable_gnss_prior().SetReferenceTime(kT0);
  EXPECT_TRUE(filter.Initialize(d.initial).ok());
  EXPECT_TRUE(filter.mutable_gnss_prior().SetOrigin(kOrigin).ok());
  const SyntheticDrive drive;
  Sample out;
  size_t next_fix = 0;
  for (const ImuSample& s : d.imu) {
    EXPECT_TRUE(filter.AddImu(s).ok());
    if (next_fix < d.gnss.size() && d.gnss[next_fix].stamp == s.stamp) {
      EXPECT_TRUE(filter.AddGnss(d.gnss[next_fix++]).ok());
    }
    const double t = s.stamp.SecondsSince(kT0);
    const double eps = 0.005;
    if (std::abs(t - epoch_s) < eps || std::abs(t - now_s) < eps) {
      const Eigen::Matrix3d R = filter.CurrentState()->T_world_body.linear();
      const Eigen::Vector3d e = so3::Log(R.transpose() * drive.At(t).R);
      if (std::abs(t - epoch_s) < eps) {
        out.e_epoch = e;
        EXPECT_TRUE(filter.MarkAttitudeEpoch().ok());
        auto c = filter.AttitudeSinceEpoch();
        EXPECT_TRUE(c.ok());
        EXPECT_EQ(c->cross, c->cov_epoch);  // right after the mark: the covariance itself
        EXPECT_EQ(c->cov_now, c->cov_epoch);
      } else {
        out.e_now = e;
        out.c = filter.AttitudeSinceEpoch().value();
      }
    }
  }
  return out;
}

TEST(InsAttitudeCorrelationTest, MonteCarloCorrelationMatchesTheFilters) {
  constexpr int kRuns = 150;
  const double epoch_s = 20.0, now_s = 30.0;
  Eigen::Vector3d s_ee = Eigen::Vector3d::Zero(), s_nn = Eigen::Vector3d::Zero(),
                  s_en = Eigen::Vector3d::Zero();
  Eigen::Vector3d rho_filter = Eigen::Vector3d::Zero();
  for (int i = 0; i < kRuns; ++i) {
    const Sample s = RunNoisyDrive(1000 + i, epoch_s, now_s);
    s_ee += s.e_epoch.cwiseAbs2();
    s_nn += s.e_now.cwiseAbs2();
    s_en += s.e_epoch.cwiseProduct(s.e_now);
    for (int a = 0; a < 3; ++a) {
      rho_filter[a] += s.c.cross(a, a) / std::sqrt(s.c.cov_now(a, a) * s.c.cov_epoch(a, a));
    }
    EXPECT_LT(s.c.now.SecondsSince(s.c.epoch), now_s - epoch_s + 1e-6);
  }
  rho_filter /= kRuns;
  const Eigen::Vector3d rho_sample = s_en.cwiseQuotient((s_ee.cwiseProduct(s_nn)).cwiseSqrt());
  for (int a = 0; a < 3; ++a) {
    SCOPED_TRACE("body axis " + std::to_string(a));
    // 150 runs: the sample correlation's standard error is (1 - rho^2) / sqrt(150) < 0.09.
    EXPECT_NEAR(rho_sample[a], rho_filter[a], 0.2)
        << "sample " << rho_sample.transpose() << " filter " << rho_filter.transpose();
    EXPECT_LT(rho_filter[a], 0.99);  // the updates between the two decorrelate them
  }
}

TEST(InsAttitudeCorrelationTest, InitialisationForgetsTheEpochAndExternalPosHasNone) {
  auto f = InsFilter::Create(InsFilter::Options());
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->MarkAttitudeEpoch().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(f->AttitudeSinceEpoch().status().code(), StatusCode::kFailedPrecondition);
  InsState init;
  init.stamp = kT0;
  ASSERT_TRUE(f->Initialize(init).ok());
  ASSERT_TRUE(f->MarkAttitudeEpoch().ok());
  EXPECT_TRUE(f->AttitudeSinceEpoch().ok());
  ASSERT_TRUE(f->Initialize(init).ok());
  EXPECT_EQ(f->AttitudeSinceEpoch().status().code(), StatusCode::kFailedPrecondition);

  auto ext = InsFilter::Create(InsFilter::Options());
  ASSERT_TRUE(ext.ok());
  ASSERT_TRUE(ext->AddExternalPose(init).ok());
  EXPECT_EQ(ext->MarkAttitudeEpoch().code(), StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace slam_mms
