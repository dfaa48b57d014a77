#include "slam_mms/eval/oxts_reference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "slam_mms/core/geodesy.hpp"
#include "slam_mms/io/georef.hpp"

namespace slam_mms::eval {
namespace {

const GeodeticPoint kOrigin{49.0131, 8.4378, 114.0};

// Records at 10 Hz along p(t) (run ENU) with velocity v(t), as an OXTS writes them: lat/lon/alt
// and the velocity in the local level frame at the record.
std::vector<StampedOxts> Records(const std::function<Eigen::Vector3d(double)>& p,
                                 const std::function<Eigen::Vector3d(double)>& v,
                                 double duration_s) {
  const GeoReference geo = GeoReference::Create(kOrigin).value();
  const Eigen::Matrix3d R_run_ecef =
      R_ecef_enu(kOrigin.latitude_deg, kOrigin.longitude_deg).transpose();
  std::vector<StampedOxts> out;
  for (int i = 0; i * 0.1 <= duration_s + 1e-9; ++i) {
    const double t = 0.1 * i;
    StampedOxts r;
    r.stamp = Timestamp::FromNanoseconds(1'000'000'000'000LL + i * 100'000'000LL);
    r.index = i;
    const GeodeticPoint g = geo.EnuToGeodetic(p(t));
    r.record.lat_deg = g.latitude_deg;
    r.record.lon_deg = g.longitude_deg;
    r.record.alt_m = g.height_m;
    const Eigen::Matrix3d R_run_local = R_run_ecef * R_ecef_enu(g.latitude_deg, g.longitude_deg);
    const Eigen::Vector3d v_local = R_run_local.transpose() * v(t);
    r.record.ve = v_local.x();
    r.record.vn = v_local.y();
    r.record.vu = v_local.z();
    r.record.yaw_rad = std::atan2(v(t).y(), v(t).x());
    out.push_back(r);
  }
  return out;
}

OxtsTrajectoryOptions Integrated() {
  OxtsTrajectoryOptions o;
  o.positions = OxtsPositions::kVelocityIntegrated;
  return o;
}

TEST(OxtsReferenceTest, IntegratedVelocitiesFollowAConsistentCircle) {
  // 10 m/s on a 50 m circle for 20 s (200 m, 4 deg per record).
  const double r = 50.0, w = 0.2;
  auto p = [&](double t) {
    return Eigen::Vector3d(r * std::sin(w * t), r - r * std::cos(w * t), 0.01 * t);
  };
  auto v = [&](double t) {
    return Eigen::Vector3d(r * w * std::cos(w * t), r * w * std::sin(w * t), 0.01);
  };
  const std::vector<StampedOxts> records = Records(p, v, 20.0);
  const Trajectory rec = OxtsTrajectory(records, kOrigin).value();
  const Trajectory vel = OxtsTrajectory(records, kOrigin, Integrated()).value();
  ASSERT_EQ(rec.size(), records.size());
  ASSERT_EQ(vel.size(), records.size());
  for (size_t i = 0; i < rec.size(); ++i) {
    EXPECT_LT((rec[i].T_world_body.translation() - p(0.1 * i)).norm(), 1e-6) << i;
    // The trapezoidal rule on a circle: a few mm over 200 m.
    EXPECT_LT((vel[i].T_world_body.translation() - p(0.1 * i)).norm(), 0.01) << i;
    EXPECT_TRUE(vel[i].T_world_body.linear().isApprox(rec[i].T_world_body.linear(), 1e-12));
  }
  const IncrementAgreement a = CompareIncrements(rec, vel, 1.0, 5.0).value();
  EXPECT_EQ(a.windows, rec.size() - 10);
  EXPECT_NEAR(a.mean_distance_m, 10.0, 0.05);
  EXPECT_LT(a.rms_pct, 0.01);
  EXPECT_LT(a.vertical_rms_pct, 0.01);
}

TEST(OxtsReferenceTest, APositionTrackWanderingOffItsVelocitiesIsMeasured) {
  // East at 10 m/s; the recorded positions drift 0.2 m/s to the north (left) on top, as a GNSS
  // position pulls a solution off its own velocity: 2 % of the distance across the motion.
  auto p = [](double t) { return Eigen::Vector3d(10.0 * t, 0.2 * t, 0.0); };
  auto v = [](double) { return Eigen::Vector3d(10.0, 0.0, 0.0); };
  const std::vector<StampedOxts> records = Records(p, v, 10.0);
  const Trajectory rec = OxtsTrajectory(records, kOrigin).value();
  const Trajectory vel = OxtsTrajectory(records, kOrigin, Integrated()).value();
  EXPECT_LT(std::abs(vel.poses().back().T_world_body.translation().y()), 1e-6);
  EXPECT_NEAR(vel.poses().back().T_world_body.translation().x(), 100.0, 1e-6);
  const IncrementAgreement a = CompareIncrements(rec, vel, 1.0, 5.0).value();
  EXPECT_NEAR(a.cross_mean_pct, 2.0, 1e-3);
  EXPECT_LT(a.cross_std_pct, 1e-3);
  EXPECT_NEAR(a.along_mean_pct, 0.0, 1e-3);
  EXPECT_NEAR(a.rms_pct, 2.0, 1e-3);
  // The other way round the difference changes sign (right of the recorded track's motion).
  const IncrementAgreement b = CompareIncrements(vel, rec, 1.0, 5.0).value();
  EXPECT_LT(b.cross_mean_pct, -1.9);
}

TEST(OxtsReferenceTest, BadRecordsAreNamed) {
  auto p = [](double t) { return Eigen::Vector3d(10.0 * t, 0.0, 0.0); };
  auto v = [](double) { return Eigen::Vector3d(10.0, 0.0, 0.0); };
  const std::vector<StampedOxts> good = Records(p, v, 2.0);

  EXPECT_EQ(OxtsTrajectory({good[0]}, kOrigin).status().code(), StatusCode::kInvalidArgument);

  std::vector<StampedOxts> back = good;
  back[5].stamp = back[4].stamp;  // not increasing
  for (const OxtsTrajectoryOptions& o : {OxtsTrajectoryOptions(), Integrated()}) {
    const Status s = OxtsTrajectory(back, kOrigin, o).status();
    EXPECT_EQ(s.code(), StatusCode::kDataLoss);
    EXPECT_NE(s.message().find("OXTS record 5 (file 5)"), std::string::npos) << s.message();
  }

  std::vector<StampedOxts> gap = good;
  for (size_t i = 10; i < gap.size(); ++i) gap[i].stamp = gap[i].stamp.PlusSeconds(2.0);
  EXPECT_TRUE(OxtsTrajectory(gap, kOrigin).ok());  // recorded positions need no continuity
  const Status s = OxtsTrajectory(gap, kOrigin, Integrated()).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_NE(s.message().find("OXTS record 10"), std::string::npos) << s.message();

  std::vector<StampedOxts> nan = good;
  nan[7].record.vn = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(OxtsTrajectory(nan, kOrigin).ok());
  const Status n = OxtsTrajectory(nan, kOrigin, Integrated()).status();
  EXPECT_EQ(n.code(), StatusCode::kDataLoss);
  EXPECT_NE(n.message().find("OXTS record 7"), std::string::npos) << n.message();
  nan = good;
  nan[3].record.lat_deg = std::numeric_limits<double>::infinity();
  EXPECT_EQ(OxtsTrajectory(nan, kOrigin).status().code(), StatusCode::kDataLoss);
}

TEST(OxtsReferenceTest, StandingGivesNoWindow) {
  auto p = [](double) { return Eigen::Vector3d(3.0, 4.0, 0.0); };
  auto v = [](double) { return Eigen::Vector3d::Zero().eval(); };
  const std::vector<StampedOxts> records = Records(p, v, 5.0);
  const Trajectory rec = OxtsTrajectory(records, kOrigin).value();
  const Trajectory vel = OxtsTrajectory(records, kOrigin, Integrated()).value();
  EXPECT_EQ(CompareIncrements(rec, vel).status().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(CompareIncrements(rec, vel, 0.0).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace slam_mms::eval
