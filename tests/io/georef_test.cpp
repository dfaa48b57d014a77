#include "slam_mms/io/georef.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>

#include "slam_mms/io/map_io.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr double kDeg = M_PI / 180.0;
const GeodeticPoint kKitti{49.013141872681, 8.4378138518088, 114.06644439697};  // KITTI 0013 start

GeoReference Make(const GeodeticPoint& o, const std::string& crs = "") {
  StatusOr<GeoReference> g = GeoReference::Create(o, crs);
  EXPECT_TRUE(g.ok()) << g.status().ToString();
  return std::move(g).value();
}

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> f;
  std::string cell;
  std::istringstream s(line);
  while (std::getline(s, cell, ',')) f.push_back(cell);
  if (!line.empty() && line.back() == ',') f.push_back("");
  return f;
}

std::vector<std::vector<std::string>> ReadCsv(const fs::path& file, std::string* header) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, *header);
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) rows.push_back(Split(line));
  return rows;
}

Eigen::Matrix3d FromEulerNedFrd(double roll, double pitch, double heading) {
  const Eigen::Matrix3d R_ned_frd = (Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()) *
                                     Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                     Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                                        .toRotationMatrix();
  Eigen::Matrix3d A;  // R_ned_enu (its own inverse)
  A << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  const Eigen::Matrix3d B = Eigen::Vector3d(1, -1, -1).asDiagonal();  // R_flu_frd
  return A * R_ned_frd * B;                                           // R_level_body (ENU, FLU)
}

double RotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

class GeorefTest : public ::testing::Test {
 protected:
  void SetUp() override { tmp_ = testing::MakeTempDir("georef"); }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(tmp_, ec);
  }
  fs::path tmp_;
};

TEST(GeoReferenceTest, DefaultIsUtmOfTheOriginAndMatchesCs2cs) {
  const GeoReference g = Make(kKitti);
  EXPECT_EQ(g.epsg(), 32632);
  EXPECT_EQ(g.crs_name(), "WGS 84 / UTM zone 32N");
  EXPECT_THAT(g.wkt1(), HasSubstr("AUTHORITY[\"EPSG\",\"32632\"]]"));
  EXPECT_THAT(g.wkt2(), HasSubstr("ID[\"EPSG\",32632]"));
  EXPECT_EQ(g.wkt1(), UtmZoneWkt(32, true));
  // `echo 49.013141872681 8.4378138518088 | cs2cs EPSG:4326 EPSG:32632 -f %.4f` (PROJ 9.1.1):
  // 458891.1966 5429068.9448; the same point in EPSG:25832 (null WGS 84 -> ETRS89 operation):
  // 458891.1966 5429068.9447.
  auto p = g.EnuToProjected(Eigen::Vector3d::Zero());
  ASSERT_TRUE(p.ok());
  EXPECT_NEAR(p->x(), 458891.1966, 0.0002);
  EXPECT_NEAR(p->y(), 5429068.9448, 0.0002);
  EXPECT_NEAR(p->z(), kKitti.height_m, 1e-9);  // heights stay ellipsoidal
  const GeoReference etrs = Make(kKitti, "EPSG:25832");
  EXPECT_EQ(etrs.epsg(), 25832);
  EXPECT_EQ(etrs.crs_name(), "ETRS89 / UTM zone 32N");
  EXPECT_THAT(etrs.wkt1(), HasSubstr("ETRS89"));
  auto q = etrs.EnuToProjected(Eigen::Vector3d::Zero());
  ASSERT_TRUE(q.ok());
  EXPECT_NEAR(q->x(), 458891.1966, 0.0002);
  EXPECT_NEAR(q->y(), 5429068.9447, 0.0002);
  // Southern hemisphere: `echo -33.92 18.42 | cs2cs EPSG:4326 EPSG:32734 -f %.4f`.
  const GeoReference cape = Make({-33.92, 18.42, 10.0});
  EXPECT_EQ(cape.epsg(), 32734);
  auto c = cape.EnuToProjected(Eigen::Vector3d::Zero());
  ASSERT_TRUE(c.ok());
  EXPECT_NEAR(c->x(), 261488.8264, 0.0002);
  EXPECT_NEAR(c->y(), 6243716.3330, 0.0002);
}

TEST(GeoReferenceTest, BadCrsIsAClearError) {
  struct Case {
    std::string crs, expected;
  };
  for (const Case& c : {Case{"EPSG:4326", "geographic"}, Case{"EPSG:4979", "geographic"},
                        Case{"EPSG:4978", "geocentric"}, Case{"EPSG:99999", "unknown to PROJ"},
                        Case{"garbage", "unknown to PROJ"}, Case{"EPSG:2277", "metres"}}) {
    StatusOr<GeoReference> g = GeoReference::Create(kKitti, c.crs);
    ASSERT_FALSE(g.ok()) << c.crs;
    EXPECT_EQ(g.status().code(), StatusCode::kInvalidArgument) << c.crs;
    EXPECT_THAT(g.status().message(), HasSubstr("'" + c.crs + "'"));
    EXPECT_THAT(g.status().message(), HasSubstr(c.expected)) << g.status().message();
  }
  // Checked before the origin is known (the app refuses a bad --crs before any processing).
  EXPECT_TRUE(GeoReference::CheckCrs("").ok());
  EXPECT_TRUE(GeoReference::CheckCrs("EPSG:25832").ok());
  EXPECT_TRUE(GeoReference::CheckCrs("EPSG:32756").ok());
  EXPECT_TRUE(GeoReference::CheckCrs("EPSG:2193").ok());  // NZTM (northing first in EPSG)
  EXPECT_THAT(GeoReference::CheckCrs("EPSG:4326").message(), HasSubstr("geographic"));
  EXPECT_THAT(GeoReference::CheckCrs("EPSG:99999").message(), HasSubstr("unknown"));
  EXPECT_FALSE(GeoReference::Create({85.0, 0.0, 0.0}).ok());  // no UTM zone
  EXPECT_FALSE(GeoReference::Create({NAN, 0.0, 0.0}, "EPSG:32632").ok());
}

TEST(GeoReferenceTest, EnuRoundTripsThroughProjInverse) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-5000.0, 5000.0);
  for (const std::string crs : {"", "EPSG:25832", "EPSG:31467"}) {
    const GeoReference g = Make(kKitti, crs);
    double worst = 0.0;
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d p(u(rng), u(rng), u(rng) / 50.0);
      auto enh = g.EnuToProjected(p);
      ASSERT_TRUE(enh.ok());
      auto back = g.ProjectedToEnu(*enh);
      ASSERT_TRUE(back.ok());
      worst = std::max(worst, (*back - p).norm());
    }
    EXPECT_LT(worst, 1e-6) << crs;
  }
}

// The map projection of the LAS writer: exact at the corners of 8 m cells, trilinear inside.
// Against the exact projection of every point: a street map around the origin and a scatter
// over 10 km x 10 km x 400 m (the second derivatives grow away from the central meridian and
// with height), in UTM, ETRS89/UTM and a Gauss-Krueger CRS.
TEST(GeoReferenceTest, InterpolatedProjectionStaysWithinMicrometresOfTheExactOne) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 20000; ++i) {  // a 300 m street: ground and facades
    const double x = 150.0 * u(rng);
    points.emplace_back(x, 10.0 * u(rng), u(rng) > 0.3 ? -1.7 + 0.02 * u(rng) : 8.0 * u(rng));
  }
  for (int i = 0; i < 20000; ++i) {
    points.emplace_back(5000.0 * u(rng), 5000.0 * u(rng), 200.0 * u(rng));
  }
  for (const std::string crs : {"", "EPSG:25832", "EPSG:31467"}) {
    const GeoReference g = Make(kKitti, crs);
    std::vector<Eigen::Vector3d> exact, interpolated;
    ASSERT_TRUE(g.EnuToProjected(points, &exact).ok());
    ASSERT_TRUE(g.EnuToProjectedInterpolated(points, &interpolated, 8.0).ok());
    ASSERT_EQ(interpolated.size(), points.size());
    double worst = 0.0;
    for (size_t i = 0; i < points.size(); ++i) {
      worst = std::max(worst, (interpolated[i] - exact[i]).cwiseAbs().maxCoeff());
    }
    EXPECT_LT(worst, 10e-6) << crs;  // the LAS file keeps 1 mm
    // Coarser cells are worse (the test can fail): 200 m cells leave millimetres.
    ASSERT_TRUE(g.EnuToProjectedInterpolated(points, &interpolated, 200.0).ok());
    double coarse = 0.0;
    for (size_t i = 0; i < points.size(); ++i) {
      coarse = std::max(coarse, (interpolated[i] - exact[i]).cwiseAbs().maxCoeff());
    }
    EXPECT_GT(coarse, 10.0 * worst) << crs;
  }
  const GeoReference g = Make(kKitti);
  std::vector<Eigen::Vector3d> out;
  EXPECT_TRUE(g.EnuToProjectedInterpolated({}, &out).ok());
  EXPECT_TRUE(out.empty());
  EXPECT_FALSE(g.EnuToProjectedInterpolated(points, &out, 0.0).ok());
  std::vector<Eigen::Vector3d> bad = {Eigen::Vector3d::Zero(), Eigen::Vector3d(NAN, 0.0, 0.0)};
  const Status s = g.EnuToProjectedInterpolated(bad, &out);
  EXPECT_FALSE(s.ok());
  EXPECT_THAT(s.message(), HasSubstr("point 1"));
}

TEST(GeoReferenceTest, GridConvergenceMatchesTheSeriesFormula) {
  // Transverse Mercator convergence (Redfearn's series): true north lies
  // gamma = dlon sin(lat) (1 + dlon^2 cos^2(lat) (1 + 3 eta^2) / 3) anticlockwise of grid north,
  // eta^2 = e'^2 cos^2(lat); the next term is O(dlon^5): < 1e-6 deg here.
  const GeoReference g = Make(kKitti);
  const double lat = kKitti.latitude_deg * kDeg, ep2 = 0.00673949674228;
  for (const double lon : {6.5, 8.4, 9.0, 11.5}) {
    auto a = g.TrueNorthFromGridNorthDeg({kKitti.latitude_deg, lon, 100.0});
    ASSERT_TRUE(a.ok());
    const double dlon = (lon - 9.0) * kDeg, c2 = std::cos(lat) * std::cos(lat);
    const double gamma = dlon * std::sin(lat) * (1 + dlon * dlon * c2 * (1 + 3 * ep2 * c2) / 3);
    EXPECT_NEAR(*a, -gamma / kDeg, 1e-5) << lon;
  }
}

TEST(GeoReferenceTest, AttitudeConventions) {
  const GeoReference g = Make(kKitti);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();  // FLU body: x forward = east
  LocalAttitude a = LocalAttitudeOf(g, T);
  EXPECT_NEAR(a.heading_deg, 90.0, 1e-9);
  EXPECT_NEAR(a.pitch_deg, 0.0, 1e-9);
  EXPECT_NEAR(a.roll_deg, 0.0, 1e-9);
  T.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_NEAR(LocalAttitudeOf(g, T).heading_deg, 0.0, 1e-9);  // facing north
  // Nose up by 5 deg: a negative rotation about the left (y) axis.
  T.linear() = Eigen::AngleAxisd(-5 * kDeg, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_NEAR(LocalAttitudeOf(g, T).pitch_deg, 5.0, 1e-9);
  // Right side down by 3 deg: a positive rotation about the forward (x) axis.
  T.linear() = Eigen::AngleAxisd(3 * kDeg, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_NEAR(LocalAttitudeOf(g, T).roll_deg, 3.0, 1e-9);
  // 10 km east the local level frame is rotated about the local up axis by the meridian
  // convergence of the ENU frame ~ dlon * sin(lat): a body with the same world attitude has a
  // heading differing by that angle.
  T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(10000.0, 0.0, 0.0);
  const GeodeticPoint p = g.EnuToGeodetic(T.translation());
  const double dlon = p.longitude_deg - kKitti.longitude_deg;
  EXPECT_NEAR(LocalAttitudeOf(g, T).heading_deg, 90.0 + dlon * std::sin(kKitti.latitude_deg * kDeg),
              2e-3);
}

TEST(GpsTimeTest, LeapSecondTable) {
  const auto at = [](int64_t posix_s) {
    return GpsMinusUtcSeconds(Timestamp::FromNanoseconds(posix_s * 1000000000));
  };
  EXPECT_EQ(*at(1317042651), 15);  // 2011-09-26 (KITTI)
  EXPECT_EQ(*at(1780000000), 18);  // 2026-05-28
  EXPECT_EQ(*at(1483228799), 17);  // 2016-12-31T23:59:59
  EXPECT_EQ(*at(1483228800), 18);  // 2017-01-01
  EXPECT_EQ(*at(315964800), 0);    // the GPS epoch
  EXPECT_EQ(*at(915148800), 13);   // 1999-01-01
  EXPECT_EQ(at(315964799).status().code(), StatusCode::kOutOfRange);
  // 2017-01-01T00:00:00 UTC is GPS week 1930, second 18 (weeks count from 1980-01-06).
  auto gps = GpsSecondsFromUtc(Timestamp::FromNanoseconds(int64_t{1483228800} * 1000000000));
  ASSERT_TRUE(gps.ok());
  EXPECT_EQ(*gps, 1930.0 * 604800.0 + 18.0);
  auto adjusted = AdjustedGpsTimeFromUtc(
      Timestamp::FromNanoseconds(int64_t{1483228800} * 1000000000 + 250000000));
  ASSERT_TRUE(adjusted.ok());
  EXPECT_NEAR(*adjusted, 1930.0 * 604800.0 + 18.25 - 1e9, 1e-7);
}

// A trajectory around the origin with covariances on every other pose.
Trajectory MakeTrajectory() {
  Trajectory t;
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 50; ++i) {
    StampedPose p;
    p.stamp = Timestamp::FromNanoseconds(int64_t{1317042651} * 1000000000 + i * 103456789LL);
    p.T_world_body = Eigen::Isometry3d::Identity();
    p.T_world_body.linear() = (Eigen::AngleAxisd(0.4 * i, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(0.05 * n(rng), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(0.05 * n(rng), Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
    p.T_world_body.translation() = Eigen::Vector3d(300 * n(rng), 300 * n(rng), 5 * n(rng));
    if (i % 2 == 0) {
      Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
      C.diagonal() << 1e-4, 4e-4, 9e-4, 0.01, 0.04, 0.09;
      p.cov_T_world_body = C;
    }
    EXPECT_TRUE(t.Add(p).ok());
  }
  return t;
}

TEST_F(GeorefTest, Wgs84AndProjectedCsvRoundTripToTheEnuPoses) {
  const Trajectory traj = MakeTrajectory();
  for (const std::string crs : {"", "EPSG:25832"}) {
    const GeoReference g = Make(kKitti, crs);
    ASSERT_TRUE(WriteTrajectoryWgs84Csv(traj, g, tmp_ / "w.csv").ok());
    ASSERT_TRUE(WriteTrajectoryProjectedCsv(traj, g, tmp_ / "p.csv").ok());
    std::string hw, hp;
    const auto w = ReadCsv(tmp_ / "w.csv", &hw);
    const auto p = ReadCsv(tmp_ / "p.csv", &hp);
    EXPECT_EQ(hw,
              "t_utc_ns,t_s,lat_deg,lon_deg,h_ellipsoid_m,roll_deg,pitch_deg,heading_deg,"
              "sigma_east_m,sigma_north_m,sigma_up_m,sigma_roll_deg,sigma_pitch_deg,"
              "sigma_heading_deg");
    EXPECT_THAT(hp, HasSubstr("t_utc_ns,t_s,easting_m,northing_m,h_m,roll_deg,pitch_deg,"
                              "grid_heading_deg,sigma_easting_m"));
    ASSERT_EQ(w.size(), traj.size());
    ASSERT_EQ(p.size(), traj.size());
    double worst_w = 0, worst_p = 0, worst_rot = 0, worst_grid = 0;
    for (size_t i = 0; i < traj.size(); ++i) {
      const StampedPose& pose = traj.poses()[i];
      ASSERT_EQ(w[i].size(), 14u);
      ASSERT_EQ(p[i].size(), 14u);
      EXPECT_EQ(std::stoll(w[i][0]), pose.stamp.nanoseconds());
      EXPECT_EQ(std::stoll(p[i][0]), pose.stamp.nanoseconds());
      EXPECT_NEAR(std::stod(w[i][1]), pose.stamp.seconds(), 1e-6);
      const GeodeticPoint geo{std::stod(w[i][2]), std::stod(w[i][3]), std::stod(w[i][4])};
      worst_w = std::max(worst_w, (g.GeodeticToEnu(geo) - pose.T_world_body.translation()).norm());
      auto back = g.ProjectedToEnu(
          Eigen::Vector3d(std::stod(p[i][2]), std::stod(p[i][3]), std::stod(p[i][4])));
      ASSERT_TRUE(back.ok());
      worst_p = std::max(worst_p, (*back - pose.T_world_body.translation()).norm());
      // Attitude back to R_world_body through the local level frame at the pose.
      const Eigen::Matrix3d R_level_body = FromEulerNedFrd(
          std::stod(w[i][5]) * kDeg, std::stod(w[i][6]) * kDeg, std::stod(w[i][7]) * kDeg);
      worst_rot = std::max(worst_rot, RotationAngle(g.R_world_level(geo) * R_level_body,
                                                    pose.T_world_body.linear()));
      auto alpha = g.TrueNorthFromGridNorthDeg(geo);
      ASSERT_TRUE(alpha.ok());
      const double dh = std::remainder(std::stod(p[i][7]) - std::stod(w[i][7]) - *alpha, 360.0);
      worst_grid = std::max(worst_grid, std::abs(dh));
      EXPECT_EQ(p[i][5], w[i][5]);  // roll and pitch do not depend on the grid
      if (pose.cov_T_world_body) {
        // sigma_up: body z sigma 0.3 m tilted by < 0.2 rad; the horizontal sum is invariant.
        const double se = std::stod(w[i][8]), sn = std::stod(w[i][9]);
        const double su = std::stod(w[i][10]);
        EXPECT_NEAR(se * se + sn * sn + su * su, 0.01 + 0.04 + 0.09, 1e-5);
        const double sE = std::stod(p[i][8]), sN = std::stod(p[i][9]);
        EXPECT_NEAR(sE * sE + sN * sN, se * se + sn * sn, 1e-5);
        EXPECT_NEAR(std::stod(w[i][10]), std::stod(p[i][10]), 1e-9);
        for (int k = 11; k < 14; ++k) EXPECT_GT(std::stod(w[i][k]), 0.5) << k;  // >= 0.01 rad
      } else {
        for (int k = 8; k < 14; ++k) EXPECT_EQ(w[i][k], "") << k;
      }
    }
    EXPECT_LT(worst_w, 0.001) << crs;
    EXPECT_LT(worst_p, 0.001) << crs;
    EXPECT_LT(worst_rot, 1e-6) << crs;
    EXPECT_LT(worst_grid, 1e-5) << crs;
  }
}

TEST_F(GeorefTest, SigmasOfALevelPoseFacingEast) {
  // At the origin, body x forward = east, y left = north, z up: sigmas map axis by axis.
  Trajectory t;
  StampedPose p;
  p.stamp = Timestamp::FromNanoseconds(int64_t{1700000000} * 1000000000);
  p.T_world_body = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  C.diagonal() << 1e-4, 4e-4, 9e-4, 0.01, 0.04, 0.09;
  p.cov_T_world_body = C;
  ASSERT_TRUE(t.Add(p).ok());
  const GeoReference g = Make(kKitti);
  ASSERT_TRUE(WriteTrajectoryWgs84Csv(t, g, tmp_ / "w.csv").ok());
  std::string h;
  const auto rows = ReadCsv(tmp_ / "w.csv", &h);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_NEAR(std::stod(rows[0][8]), 0.1, 1e-5);
  EXPECT_NEAR(std::stod(rows[0][9]), 0.2, 1e-5);
  EXPECT_NEAR(std::stod(rows[0][10]), 0.3, 1e-5);
  EXPECT_NEAR(std::stod(rows[0][11]), 0.01 / kDeg, 1e-4);  // roll about forward
  EXPECT_NEAR(std::stod(rows[0][12]), 0.02 / kDeg, 1e-4);  // pitch about left
  EXPECT_NEAR(std::stod(rows[0][13]), 0.03 / kDeg, 1e-4);  // heading about up
}

TEST_F(GeorefTest, GeorefJsonNamesOriginCrsAndVerticalDatum) {
  const GeoReference g = Make(kKitti, "EPSG:25832");
  ASSERT_TRUE(WriteGeorefJson(g, tmp_ / "georef.json").ok());
  std::ifstream in(tmp_ / "georef.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_DOUBLE_EQ(j["origin"]["latitude_deg"].get<double>(), kKitti.latitude_deg);
  EXPECT_DOUBLE_EQ(j["origin"]["longitude_deg"].get<double>(), kKitti.longitude_deg);
  EXPECT_DOUBLE_EQ(j["origin"]["height_m"].get<double>(), kKitti.height_m);
  EXPECT_EQ(j["crs"]["epsg"].get<int>(), 25832);
  EXPECT_EQ(j["crs"]["requested"].get<std::string>(), "EPSG:25832");
  EXPECT_EQ(j["crs"]["wkt1_gdal"].get<std::string>(), g.wkt1());
  EXPECT_THAT(j["crs"]["wkt2_2019"].get<std::string>(), HasSubstr("ETRS89 / UTM zone 32N"));
  EXPECT_NEAR(j["crs"]["origin_easting_m"].get<double>(), 458891.1966, 0.0002);
  EXPECT_EQ(j["vertical"]["kind"].get<std::string>(), "ellipsoidal");
  EXPECT_EQ(j["vertical"]["datum"].get<std::string>(), "WGS 84 ellipsoid");
  EXPECT_FALSE(j["vertical"]["geoid_applied"].get<bool>());
  EXPECT_THAT(j["world_frame"]["axes"].get<std::string>(), HasSubstr("x east, y north, z up"));
  EXPECT_THAT(j["time"]["t_utc_ns"].get<std::string>(), HasSubstr("UTC"));
  EXPECT_FALSE(j["crs"]["operation"]["name"].get<std::string>().empty());
}

// A map of `scans` scans of `per_scan` points each, a scan every 0.1 s, points in firing order.
MapCloud MakeTimedMap(int scans, int per_scan, float extent_m) {
  MapCloud m;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-extent_m, extent_m);
  const int64_t t0 = int64_t{1317042651} * 1000000000;
  for (int s = 0; s < scans; ++s) {
    for (int k = 0; k < per_scan; ++k) {
      m.cloud.Add(Eigen::Vector3f(u(rng), u(rng), u(rng) / 20.0f), 0.5f);
      // Distinct times in firing order, 0.1 s per scan.
      m.time_ns.push_back(t0 + s * 100000000LL + k * (100000000LL / per_scan));
      m.source_id.push_back(static_cast<uint16_t>(s));
      m.classification.push_back(static_cast<uint8_t>(k % 3 == 0 ? 2 : 0));
    }
  }
  // Shuffle the map's order (the run's map is ordered by voxel, not by time).
  std::vector<size_t> perm(m.cloud.size());
  for (size_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  MapCloud out;
  for (const size_t i : perm) {
    out.cloud.Add(m.cloud.points()[i], m.cloud.intensities()[i]);
    out.time_ns.push_back(m.time_ns[i]);
    out.source_id.push_back(m.source_id[i]);
    out.classification.push_back(m.classification[i]);
  }
  return out;
}

// Checks `las` against `map`: each LAS point matched to its map point by GPS time.
void CheckLasAgainstMap(const LasCloud& las, const MapCloud& map, const GeoReference& g,
                        std::set<size_t>* seen) {
  std::map<int64_t, size_t> by_time;
  for (size_t i = 0; i < map.cloud.size(); ++i) by_time[map.time_ns[i]] = i;
  ASSERT_EQ(las.gps_time.size(), las.points_utm.size());
  std::map<uint16_t, double> last_time;
  double worst = 0.0;
  for (size_t k = 0; k < las.points_utm.size(); ++k) {
    // Adjusted GPS time - leap seconds = UTC; match to the map's ns times (1 us tolerance).
    const double utc_s = las.gps_time[k] + 1e9 - 15.0 + 315964800.0;
    const auto t_ns = static_cast<int64_t>(std::llround(utc_s * 1e6)) * 1000;
    auto it = by_time.lower_bound(t_ns - 1000);
    ASSERT_NE(it, by_time.end());
    ASSERT_LE(std::abs(it->first - t_ns), 1000) << k;
    const size_t i = it->second;
    EXPECT_TRUE(seen->insert(i).second) << "point " << i << " twice";
    EXPECT_EQ(las.point_source_id[k], map.source_id[i]);
    EXPECT_EQ(las.classification[k], map.classification[i]);
    EXPECT_EQ(las.user_data[k], 0);
    // Monotone GPS time within each point source ID (scan) through the file.
    auto [prev, inserted] = last_time.emplace(las.point_source_id[k], las.gps_time[k]);
    if (!inserted) {
      EXPECT_GT(las.gps_time[k], prev->second) << k;
      prev->second = las.gps_time[k];
    }
    auto back = g.ProjectedToEnu(las.points_utm[k]);
    ASSERT_TRUE(back.ok());
    worst = std::max(worst, (*back - map.cloud.points()[i].cast<double>()).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 0.0005 + 1e-4);  // 1 mm quantisation (+ float32 of the input)
}

TEST_F(GeorefTest, LasCarriesGpsTimeSourceIdAndClassAndRoundTrips) {
  const MapCloud map = MakeTimedMap(20, 500, 400.0f);
  for (const std::string crs : {"", "EPSG:25832"}) {
    const GeoReference g = Make(kKitti, crs);
    ASSERT_TRUE(WriteLas(map, g, tmp_ / "m.las", LasWriteOptions()).ok());
    auto las = ReadLas(tmp_ / "m.las");
    ASSERT_TRUE(las.ok()) << las.status().ToString();
    EXPECT_EQ(las->wkt, g.wkt1());
    EXPECT_TRUE(las->global_encoding & 1);  // adjusted standard GPS time
    ASSERT_EQ(las->points_utm.size(), map.cloud.size());
    std::set<size_t> seen;
    CheckLasAgainstMap(*las, map, g, &seen);
    EXPECT_EQ(seen.size(), map.cloud.size());
    // The whole file in time order.
    EXPECT_TRUE(std::is_sorted(las->gps_time.begin(), las->gps_time.end()));
  }
  // Without per-point data: GPS time 0, the options' source ID, class 0.
  MapCloud plain;
  plain.cloud = map.cloud;
  LasWriteOptions o;
  o.point_source_id = 7;
  ASSERT_TRUE(WriteLas(plain, kKitti, tmp_ / "p.las", o).ok());
  auto las = ReadLas(tmp_ / "p.las");
  ASSERT_TRUE(las.ok());
  EXPECT_EQ(las->gps_time.front(), 0.0);
  EXPECT_EQ(las->point_source_id.back(), 7);
  EXPECT_EQ(las->classification.back(), 0);
  // Inconsistent arrays are refused.
  MapCloud bad = map;
  bad.time_ns.pop_back();
  EXPECT_THAT(WriteLas(bad, kKitti, tmp_ / "b.las").message(), HasSubstr("MapCloud::time_ns"));
}

TEST_F(GeorefTest, TilesCoverEveryPointExactlyOnce) {
  const MapCloud map = MakeTimedMap(10, 2000, 350.0f);
  const GeoReference g = Make(kKitti);
  const double size = 100.0;
  auto tiles = WriteLasTiles(map, g, tmp_ / "tiles", size, LasWriteOptions());
  ASSERT_TRUE(tiles.ok()) << tiles.status().ToString();
  EXPECT_GE(tiles->size(), 49u);  // 700 m x 700 m in 100 m cells
  std::set<size_t> seen;
  size_t total = 0;
  for (const LasTile& t : *tiles) {
    auto las = ReadLas(tmp_ / "tiles" / t.file);
    ASSERT_TRUE(las.ok()) << t.file;
    ASSERT_EQ(las->points_utm.size(), t.num_points);
    total += t.num_points;
    char name[96];
    std::snprintf(name, sizeof(name), "tile_%.0f_%.0f.las", t.min_easting_m, t.min_northing_m);
    EXPECT_EQ(t.file, name);
    for (const Eigen::Vector3d& p : las->points_utm) {
      // Inside the cell (up to the 1 mm quantisation at its edges).
      EXPECT_GE(p.x(), t.min_easting_m - 0.001);
      EXPECT_LE(p.x(), t.min_easting_m + size + 0.001);
      EXPECT_GE(p.y(), t.min_northing_m - 0.001);
      EXPECT_LE(p.y(), t.min_northing_m + size + 0.001);
    }
    CheckLasAgainstMap(*las, map, g, &seen);
  }
  EXPECT_EQ(total, map.cloud.size());
  EXPECT_EQ(seen.size(), map.cloud.size());
  std::ifstream in(tmp_ / "tiles" / "index.json");
  const nlohmann::json index = nlohmann::json::parse(in);
  ASSERT_EQ(index["tiles"].size(), tiles->size());
  EXPECT_EQ(index["points"].get<size_t>(), map.cloud.size());
  for (const auto& t : index["tiles"]) {
    EXPECT_TRUE(fs::exists(tmp_ / "tiles" / t["file"].get<std::string>()));
  }
  EXPECT_FALSE(WriteLasTiles(map, g, tmp_ / "t0", 0.0, LasWriteOptions()).ok());
}

}  // namespace
}  // namespace slam_mms
