// GnssSimulator: error statistics match the configured sigmas; outages are respected.
#include <gtest/gtest.h>

#include <cmath>

#include "slam_mms/sim/gnss_simulator.hpp"

namespace slam_mms::sim {
namespace {

struct Stats {
  double rms_e = 0, rms_n = 0, rms_u = 0, mean_sigma_h = 0, sd_sigma_h = 0;
};

Stats Collect(GnssSimulator::Options o, int seeds, double seconds) {
  o.urban_canyon_scale = 0.0;
  double se = 0, sn = 0, su = 0, ss = 0, ss2 = 0;
  long n = 0;
  for (int seed = 0; seed < seeds; ++seed) {
    GnssSimulator g(o, 1000 + seed);
    for (int k = 0; k < static_cast<int>(seconds * o.rate_hz); ++k) {
      const GnssSample s = g.Step(k / o.rate_hz, 0.0);
      EXPECT_EQ(s.state, o.best_state);
      se += s.error_enu_m.x() * s.error_enu_m.x();
      sn += s.error_enu_m.y() * s.error_enu_m.y();
      su += s.error_enu_m.z() * s.error_enu_m.z();
      ss += s.sigma_horizontal_m;
      ss2 += s.sigma_horizontal_m * s.sigma_horizontal_m;
      ++n;
    }
  }
  Stats st;
  st.rms_e = std::sqrt(se / n);
  st.rms_n = std::sqrt(sn / n);
  st.rms_u = std::sqrt(su / n);
  st.mean_sigma_h = ss / n;
  st.sd_sigma_h = std::sqrt(std::max(0.0, ss2 / n - st.mean_sigma_h * st.mean_sigma_h));
  return st;
}

TEST(GnssSimulatorTest, RtkFixedErrorsMatchTheConfiguredSigmas) {
  GnssSimulator::Options o;
  o.best_state = GnssState::kRtkFixed;
  const Stats s = Collect(o, 300, 20.0);
  // Gauss-Markov bias (sigma) plus epoch white noise (0.2 sigma): total sqrt(1.04) sigma.
  const double k = std::sqrt(1.04);
  EXPECT_NEAR(s.rms_e, k * o.sigma_fixed_h_m, 0.12 * k * o.sigma_fixed_h_m);
  EXPECT_NEAR(s.rms_n, k * o.sigma_fixed_h_m, 0.12 * k * o.sigma_fixed_h_m);
  EXPECT_NEAR(s.rms_u, k * o.sigma_fixed_v_m, 0.12 * k * o.sigma_fixed_v_m);
  // The reported sigma is close to the configured one but varies (not a copy of the truth).
  EXPECT_NEAR(s.mean_sigma_h, o.sigma_fixed_h_m, 0.1 * o.sigma_fixed_h_m);
  EXPECT_GT(s.sd_sigma_h, 0.1 * o.sigma_fixed_h_m);
}

TEST(GnssSimulatorTest, SinglePointErrorsMatchTheConfiguredSigmas) {
  GnssSimulator::Options o;
  o.best_state = GnssState::kSps;
  o.multipath_rate_hz = 0.0;  // jumps add to the bias; test the configured part alone
  const Stats s = Collect(o, 300, 20.0);
  const double k = std::sqrt(1.04);
  EXPECT_NEAR(s.rms_e, k * o.sigma_sps_h_m, 0.12 * k * o.sigma_sps_h_m);
  EXPECT_NEAR(s.rms_n, k * o.sigma_sps_h_m, 0.12 * k * o.sigma_sps_h_m);
  EXPECT_NEAR(s.rms_u, k * o.sigma_sps_v_m, 0.12 * k * o.sigma_sps_v_m);
}

TEST(GnssSimulatorTest, ErrorsAreCorrelatedInTime) {
  GnssSimulator::Options o;
  o.best_state = GnssState::kSps;
  o.urban_canyon_scale = 0.0;
  GnssSimulator g(o, 5);
  // Consecutive 10 Hz epochs differ by far less than the error itself (tau 60 s).
  double diff2 = 0, err2 = 0;
  Eigen::Vector3d prev = Eigen::Vector3d::Zero();
  for (int k = 0; k < 6000; ++k) {
    const GnssSample s = g.Step(k * 0.01, 0.0);
    if (k % 10 == 0 && k > 0) diff2 += (s.error_enu_m - prev).head<2>().squaredNorm();
    if (k % 10 == 0) prev = s.error_enu_m;
    err2 += s.error_enu_m.head<2>().squaredNorm() / 10.0;
  }
  EXPECT_LT(diff2, 0.25 * err2);
}

TEST(GnssSimulatorTest, ScriptedOutagesAreRespected) {
  GnssSimulator::Options o;
  o.urban_canyon_scale = 0.0;
  o.outages = {{10.0, 5.0}, {70.0, 2.0}};
  GnssSimulator g(o, 11);
  double sigma_start = -1, sigma_end = -1;
  GnssState prev = GnssState::kRtkFixed;
  for (int k = 0; k < 8000; ++k) {
    const double t = k * 0.01;
    const GnssSample s = g.Step(t, 0.0);
    const bool in = (t >= 10.0 && t < 15.0) || (t >= 70.0 && t < 72.0);
    EXPECT_EQ(s.in_scripted_outage, in) << t;
    if (in) {
      EXPECT_EQ(s.state, GnssState::kNone) << t;
      EXPECT_LE(s.num_satellites, 3);
      if (sigma_start < 0) sigma_start = s.sigma_horizontal_m;
      if (t < 15.0) sigma_end = s.sigma_horizontal_m;
    } else if (t < 10.0) {
      EXPECT_EQ(s.state, GnssState::kRtkFixed) << t;
    } else if (t >= 15.0 && t < 70.0) {
      // Re-acquisition climbs one state at a time: SPS, float (after 5-15 s), fixed (10-30 s
      // later).
      EXPECT_GE(static_cast<int>(s.state), static_cast<int>(prev)) << t;
      EXPECT_LE(static_cast<int>(s.state), static_cast<int>(prev) + 1) << t;
      if (t < 20.0)
        EXPECT_NE(s.state, GnssState::kRtkFixed) << "RTK needs time to converge, t=" << t;
      if (t > 61.0) EXPECT_EQ(s.state, GnssState::kRtkFixed) << "re-converged by t=" << t;
    }
    prev = s.state;
  }
  EXPECT_GT(sigma_end, sigma_start) << "reported sigma grows while dead-reckoning";
}

TEST(GnssSimulatorTest, UrbanCanyonDegradesTheFix) {
  GnssSimulator::Options o;
  GnssSimulator g(o, 3);
  GnssState worst = GnssState::kRtkFixed;
  for (int k = 0; k < 1000; ++k) worst = std::min(worst, g.Step(k * 0.01, 0.95).state);
  EXPECT_EQ(worst, GnssState::kNone);
}

TEST(GnssSimulatorTest, ValidateNamesTheField) {
  GnssSimulator::Options o;
  o.outages = {{1.0, -2.0}};
  const Status s = o.Validate();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("outages[0]"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace slam_mms::sim
