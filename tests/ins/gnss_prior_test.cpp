#include "slam_mms/ins/gnss_prior.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <random>

namespace slam_mms {
namespace {

const Timestamp kT0 = Timestamp::FromSeconds(1317000000.0);

GnssFix Fix(double t, double lat, double lon, double h, GnssFixType type = GnssFixType::kRtkFixed,
            double sigma = 0.02) {
  GnssFix f;
  f.stamp = kT0.PlusSeconds(t);
  f.latitude_deg = lat;
  f.longitude_deg = lon;
  f.height_m = h;
  f.sigma_horizontal_m = sigma;
  f.sigma_vertical_m = 1.5 * sigma;
  f.type = type;
  return f;
}

// A fix at ENU position p of the prior's world frame.
GnssFix FixAt(const GnssPrior& prior, double t, const Eigen::Vector3d& p,
              GnssFixType type = GnssFixType::kRtkFixed, double sigma = 0.02) {
  const GeodeticPoint g = prior.ToGeodetic(p).value();
  return Fix(t, g.latitude_deg, g.longitude_deg, g.height_m, type, sigma);
}

TEST(GnssPriorTest, EnuConversionMatchesGeographicLib) {
  GnssPrior prior;
  // First fix invalid: it must not anchor the world frame.
  auto r0 = prior.Process(Fix(0.0, 10.0, 10.0, 0.0, GnssFixType::kNone), nullptr);
  ASSERT_TRUE(r0.ok());
  EXPECT_EQ(r0->decision, GnssDecision::kReject);
  EXPECT_FALSE(prior.has_origin());
  auto r1 = prior.Process(Fix(0.1, 49.011, 8.4165, 112.3), nullptr);
  ASSERT_TRUE(r1.ok());
  EXPECT_EQ(r1->decision, GnssDecision::kUse);
  ASSERT_TRUE(prior.has_origin());
  EXPECT_EQ(prior.origin().latitude_deg, 49.011);
  EXPECT_NEAR(r1->measurement.p_world_antenna.norm(), 0.0, 1e-9);
  const GeographicLib::LocalCartesian ref(49.011, 8.4165, 112.3);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.05, 0.05);  // about +-5 km
  for (int k = 0; k < 100; ++k) {
    const GeodeticPoint g{49.011 + u(rng), 8.4165 + u(rng), 112.3 + 1000 * u(rng)};
    Eigen::Vector3d expected;
    ref.Forward(g.latitude_deg, g.longitude_deg, g.height_m, expected.x(), expected.y(),
                expected.z());
    const Eigen::Vector3d p = prior.ToWorld(g).value();
    EXPECT_LT((p - expected).norm(), 1e-6);
    const GeodeticPoint back = prior.ToGeodetic(p).value();
    EXPECT_NEAR(back.latitude_deg, g.latitude_deg, 1e-10);
    EXPECT_NEAR(back.longitude_deg, g.longitude_deg, 1e-10);
    EXPECT_NEAR(back.height_m, g.height_m, 1e-6);
  }
  // Sanity of the axes: north is +y, east is +x.
  EXPECT_GT(prior.ToWorld({49.012, 8.4165, 112.3}).value().y(), 100.0);
  EXPECT_GT(prior.ToWorld({49.011, 8.418, 112.3}).value().x(), 100.0);
  EXPECT_FALSE(prior.SetOrigin({1, 2, 3}).ok());
}

TEST(GnssPriorTest, FloorsFixTypesAndSigmaDecide) {
  GnssPrior prior;
  ASSERT_TRUE(prior.SetOrigin({49.0, 8.4, 100.0}).ok());
  const Eigen::Vector3d p(10, 20, 1);
  // RTK fixed with a tiny sigma: used, floored.
  auto r = prior.Process(FixAt(prior, 0.0, p, GnssFixType::kRtkFixed, 0.001), nullptr);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->decision, GnssDecision::kUse);
  EXPECT_NEAR(r->measurement.cov_world_antenna(0, 0), 0.02 * 0.02, 1e-12);
  EXPECT_NEAR(r->measurement.cov_world_antenna(2, 2), 0.03 * 0.03, 1e-12);
  EXPECT_LT((r->measurement.p_world_antenna - p).norm(), 1e-6);
  // Single point: down-weighted (variance x4).
  r = prior.Process(FixAt(prior, 0.1, p, GnssFixType::kSingle, 1.5), nullptr);
  EXPECT_EQ(r->decision, GnssDecision::kDownWeight);
  EXPECT_NEAR(r->measurement.cov_world_antenna(0, 0), 4.0 * 1.5 * 1.5, 1e-9);
  // No fix: rejected; reported sigma above the maximum: rejected.
  EXPECT_EQ(prior.Process(FixAt(prior, 0.2, p, GnssFixType::kNone), nullptr)->decision,
            GnssDecision::kReject);
  EXPECT_EQ(prior.Process(FixAt(prior, 0.3, p, GnssFixType::kSingle, 25.0), nullptr)->decision,
            GnssDecision::kReject);
  // Out of order.
  EXPECT_FALSE(prior.Process(FixAt(prior, 0.25, p), nullptr).ok());
  EXPECT_EQ(prior.num_used(), 1);
  EXPECT_EQ(prior.num_downweighted(), 1);
  EXPECT_EQ(prior.num_rejected(), 2);
}

TEST(GnssPriorTest, InnovationTestRejectsMultipathJumps) {
  GnssPrior prior;
  ASSERT_TRUE(prior.SetOrigin({49.0, 8.4, 100.0}).ok());
  GnssPrediction pred;
  pred.p_world_antenna = Eigen::Vector3d(100, 50, 2);
  pred.cov_world_antenna = Eigen::Vector3d(0.1, 0.1, 0.2).asDiagonal();  // ~0.3 m sigma
  double t = 0.0;
  for (double jump : {10.0, 20.0, 50.0, 100.0}) {
    for (const Eigen::Vector3d& dir :
         {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0.6, -0.8, 0), Eigen::Vector3d(0, 0, 1)}) {
      auto r = prior.Process(FixAt(prior, t += 0.1, pred.p_world_antenna + jump * dir), &pred);
      ASSERT_TRUE(r.ok());
      EXPECT_EQ(r->decision, GnssDecision::kReject) << jump << " m";
      EXPECT_GT(r->innovation_chi2, 100.0);
    }
  }
  // Consistent fixes are used; a 1.5 m innovation (chi2 ~ 20) is rejected, 1.1 m down-weighted.
  EXPECT_EQ(
      prior
          .Process(FixAt(prior, t += 0.1, pred.p_world_antenna + Eigen::Vector3d(0.2, 0.1, 0)),
                   &pred)
          ->decision,
      GnssDecision::kUse);
  EXPECT_EQ(
      prior
          .Process(FixAt(prior, t += 0.1, pred.p_world_antenna + Eigen::Vector3d(1.1, 0, 0)), &pred)
          ->decision,
      GnssDecision::kDownWeight);
  EXPECT_EQ(
      prior
          .Process(FixAt(prior, t += 0.1, pred.p_world_antenna + Eigen::Vector3d(1.5, 0, 0)), &pred)
          ->decision,
      GnssDecision::kReject);
  // Without an estimate: a speed test against the last used fix.
  GnssPrior p2;
  ASSERT_TRUE(p2.SetOrigin({49.0, 8.4, 100.0}).ok());
  EXPECT_EQ(p2.Process(FixAt(p2, 0.0, {0, 0, 0}), nullptr)->decision, GnssDecision::kUse);
  EXPECT_EQ(p2.Process(FixAt(p2, 0.1, {1, 0, 0}), nullptr)->decision, GnssDecision::kUse);
  EXPECT_EQ(p2.Process(FixAt(p2, 0.2, {51, 0, 0}), nullptr)->decision, GnssDecision::kReject);
  EXPECT_EQ(p2.Process(FixAt(p2, 0.3, {3, 0, 0}), nullptr)->decision, GnssDecision::kUse);
}

TEST(GnssPriorTest, ReacquiresAfterALongRejectionStreak) {
  GnssPrior::Options o;
  o.max_rejection_streak_s = 2.0;
  GnssPrior prior = GnssPrior::Create(o).value();
  ASSERT_TRUE(prior.SetOrigin({49.0, 8.4, 100.0}).ok());
  GnssPrediction pred;
  pred.cov_world_antenna = 0.01 * Eigen::Matrix3d::Identity();
  int rejected = 0;
  GnssDecision last = GnssDecision::kReject;
  for (int k = 0; k <= 25; ++k) {
    last = prior.Process(FixAt(prior, 0.1 * k, {30, 0, 0}), &pred)->decision;
    if (last == GnssDecision::kReject) ++rejected;
    if (last != GnssDecision::kReject) break;
  }
  EXPECT_EQ(rejected, 20);  // 0.0 .. 1.9 s rejected, the fix at 2.0 s re-acquires
  EXPECT_EQ(last, GnssDecision::kUse);
}

TEST(GnssPriorTest, OutageWindowsAndAvailability) {
  GnssPrior prior;
  ASSERT_TRUE(prior.SetOrigin({49.0, 8.4, 100.0}).ok());
  prior.SetReferenceTime(kT0);
  ASSERT_TRUE(prior.AddOutageWindow(2.0, 3.0).ok());  // [2, 5)
  EXPECT_FALSE(prior.AddOutageWindow(1.0, 0.0).ok());
  for (int k = 0; k <= 80; ++k) {
    const double t = 0.1 * k;
    const GnssFixType type = t >= 6.95 ? GnssFixType::kSingle : GnssFixType::kRtkFixed;
    auto r = prior.Process(
        FixAt(prior, t, {k * 1.0, 0, 0}, type, type == GnssFixType::kSingle ? 1.0 : 0.02), nullptr);
    ASSERT_TRUE(r.ok());
    const bool withheld = t >= 2.0 - 1e-9 && t < 5.0 - 1e-9;
    EXPECT_EQ(r->decision == GnssDecision::kWithheld, withheld) << t;
  }
  EXPECT_TRUE(prior.IsWithheld(kT0.PlusSeconds(2.0)));
  EXPECT_TRUE(prior.IsWithheld(kT0.PlusSeconds(4.999)));
  EXPECT_FALSE(prior.IsWithheld(kT0.PlusSeconds(5.0)));
  EXPECT_FALSE(prior.IsWithheld(kT0.PlusSeconds(1.999)));
  EXPECT_EQ(prior.num_withheld(), 30);
  EXPECT_EQ(prior.AvailabilityAt(kT0.PlusSeconds(1.0)), GnssAvailability::kValid);
  EXPECT_EQ(prior.AvailabilityAt(kT0.PlusSeconds(3.0)), GnssAvailability::kValid);  // < timeout 1.5
  EXPECT_EQ(prior.AvailabilityAt(kT0.PlusSeconds(4.0)), GnssAvailability::kOutage);
  EXPECT_EQ(prior.AvailabilityAt(kT0.PlusSeconds(6.0)), GnssAvailability::kValid);
  EXPECT_EQ(prior.AvailabilityAt(kT0.PlusSeconds(7.5)), GnssAvailability::kDegraded);
  EXPECT_EQ(prior.AvailabilityAt(kT0.PlusSeconds(20.0)), GnssAvailability::kOutage);
  const auto iv = prior.AvailabilityIntervals();
  ASSERT_EQ(iv.size(), 4u);
  EXPECT_EQ(iv[0].availability, GnssAvailability::kValid);
  EXPECT_EQ(iv[1].availability, GnssAvailability::kOutage);
  EXPECT_NEAR(iv[1].start.SecondsSince(kT0), 1.9 + 1.5, 1e-6);
  EXPECT_NEAR(iv[1].end.SecondsSince(kT0), 5.0, 1e-6);
  EXPECT_EQ(iv[2].availability, GnssAvailability::kValid);
  EXPECT_EQ(iv[3].availability, GnssAvailability::kDegraded);
  EXPECT_NEAR(iv[3].start.SecondsSince(kT0), 7.0, 1e-6);
}

TEST(GnssPriorTest, MeasurementIsTheAntennaPosition) {
  GnssPrior::Options o;
  o.t_body_antenna = Eigen::Vector3d(0.0, 0.0, 1.5);
  GnssPrior prior = GnssPrior::Create(o).value();
  ASSERT_TRUE(prior.SetOrigin({49.0, 8.4, 100.0}).ok());
  auto r = prior.Process(FixAt(prior, 0.0, {5, 6, 1.5}), nullptr);
  ASSERT_TRUE(r.ok() && r->usable());
  // The measurement is the antenna's position; the lever arm enters in the factor
  // (backend/gnss_position_factor.hpp, tested in tests/backend).
  EXPECT_LT((r->measurement.p_world_antenna - Eigen::Vector3d(5, 6, 1.5)).norm(), 1e-6);
  // Invalid options are named.
  GnssPrior::Options bad;
  bad.sigma_floor_horizontal_m = 0.0;
  const Status s = GnssPrior::Create(bad).status();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("sigma_floor_horizontal_m"), std::string::npos);
}

}  // namespace
}  // namespace slam_mms
