#include "slam_mms/merge/drive_result_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;

DriveResult Sample() {
  DriveResult r;
  r.origin = {48.1234567891, 11.9876543219, 512.345};
  r.T_body_lidar.translation() << 0.81, -0.32, 0.8;
  r.T_body_lidar.linear() =
      Eigen::AngleAxisd(0.01, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  r.gnss_availability.push_back({Timestamp::FromNanoseconds(1700000000123456789),
                                 Timestamp::FromNanoseconds(1700000010000000000),
                                 GnssAvailability::kValid});
  r.gnss_availability.push_back({Timestamp::FromNanoseconds(1700000010000000000),
                                 Timestamp::FromNanoseconds(1700000040000000000),
                                 GnssAvailability::kOutage});
  for (int k = 0; k < 3; ++k) {
    DriveSubmap s;
    s.id = 10 + k;
    s.start = Timestamp::FromNanoseconds(1700000000000000000 + k * 1000000007LL);
    s.end = s.start.PlusSeconds(0.9);
    s.T_world_submap.translation() << 1.0 / 3.0 + k, -2.0 / 7.0, 0.1;
    s.T_world_submap.linear() =
        Eigen::AngleAxisd(0.3 * k + 0.1, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    for (int j = 0; j < 2; ++j) {
      SubmapScanPose p;
      p.submap = s.id;
      p.scan_id = 100 * k + j;
      p.stamp = s.start.PlusSeconds(0.1 * j);
      p.T_submap_scan.translation() << 0.7 * j, 0.01, 0.0;
      s.scans.push_back(p);
      Matrix6d c = Matrix6d::Identity() * (1e-4 + j);
      c(0, 1) = c(1, 0) = 1e-7;
      s.cov_submap_scan.push_back(c);
    }
    for (int i = 0; i < 50; ++i) {
      s.map_cloud.Add(Eigen::Vector3f(i * 0.1f, k, 0.3f), 0.25f * (i % 4));
      if (i % 2 == 0) s.registration_cloud.Add(Eigen::Vector3f(i * 0.1f, k, 0.3f), 0.5f);
    }
    r.submaps.push_back(s);
  }
  SubmapGraphFactor reg;
  reg.kind = SubmapFactorKind::kRegistration;
  reg.a = 10;
  reg.b = 11;
  reg.T.translation() << 1.0, 0.1, 0.0;
  reg.loss = RobustLoss::Huber(3.0);
  SubmapGraphFactor gnss;
  gnss.kind = SubmapFactorKind::kGnss;
  gnss.a = gnss.b = 12;
  gnss.p_world_antenna << 3.3, -0.2, 1.9;
  gnss.covariance = Matrix6d::Zero();
  gnss.covariance.topLeftCorner<3, 3>() = 0.0004 * Eigen::Matrix3d::Identity();
  gnss.t_body_antenna << 0.1, 0.2, 0.9;
  SubmapGraphFactor prior;
  prior.kind = SubmapFactorKind::kPosePrior;
  prior.a = prior.b = 11;
  SubmapGraphFactor chain;
  chain.kind = SubmapFactorKind::kAttitudeChain;
  chain.a = 11;
  chain.b = 12;
  chain.T.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  chain.T_a.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  chain.covariance = Matrix6d::Zero();
  chain.covariance.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * 3e-6;
  chain.transition << 0.9200444146293233, 0.01, 0.0, -0.01, 0.92, 0.0, 0.0, 0.0, 0.25;
  SubmapGraphFactor bias;  // level 2's Gauss-Markov GNSS bias nodes
  bias.kind = SubmapFactorKind::kGnssBias;
  bias.a = bias.b = -1;
  bias.gnss_bias = 0;
  bias.covariance = Matrix6d::Zero();
  bias.covariance.topLeftCorner<3, 3>() = 0.09 * Eigen::Matrix3d::Identity();
  SubmapGraphFactor link = bias;
  link.kind = SubmapFactorKind::kGnssBiasLink;
  link.gnss_bias = 1;
  link.gnss_bias_from = 0;
  link.transition = 0.9672161004820059 * Eigen::Matrix3d::Identity();
  link.covariance.topLeftCorner<3, 3>() = 0.0058 * Eigen::Matrix3d::Identity();
  r.factors = {reg, gnss, prior, chain, bias, link};
  return r;
}

std::string Slurp(const fs::path& f) {
  std::ifstream in(f, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(DriveResultIoTest, RoundTripsLosslessly) {
  const fs::path dir = testing::MakeTempDir("drive_result_rt");
  const DriveResult a = Sample();
  ASSERT_TRUE(WriteDriveResult(a, dir / "one").ok());
  auto b = ReadDriveResult(dir / "one");
  ASSERT_TRUE(b.ok()) << b.status().ToString();
  EXPECT_EQ(b->origin.latitude_deg, a.origin.latitude_deg);
  EXPECT_EQ(b->origin.height_m, a.origin.height_m);
  ASSERT_EQ(b->submaps.size(), 3u);
  EXPECT_TRUE(b->submaps[1].T_world_submap.isApprox(a.submaps[1].T_world_submap, 1e-15));
  EXPECT_EQ(b->submaps[2].scans[1].stamp, a.submaps[2].scans[1].stamp);
  EXPECT_EQ(b->submaps[2].scans[1].scan_id, 201);
  EXPECT_EQ(b->submaps[0].cov_submap_scan[1], a.submaps[0].cov_submap_scan[1]);
  EXPECT_EQ(b->submaps[1].map_cloud.size(), 50u);
  EXPECT_EQ(b->submaps[1].registration_cloud.size(), 25u);
  EXPECT_EQ(b->submaps[1].map_cloud.intensities()[3], 0.75f);
  ASSERT_EQ(b->factors.size(), 6u);
  EXPECT_EQ(b->factors[4].kind, SubmapFactorKind::kGnssBias);
  EXPECT_EQ(b->factors[4].gnss_bias, 0);
  EXPECT_EQ(b->factors[4].covariance, a.factors[4].covariance);
  EXPECT_EQ(b->factors[5].kind, SubmapFactorKind::kGnssBiasLink);
  EXPECT_EQ(b->factors[5].gnss_bias, 1);
  EXPECT_EQ(b->factors[5].gnss_bias_from, 0);
  EXPECT_EQ(b->factors[5].transition, a.factors[5].transition);
  EXPECT_EQ(b->factors[5].covariance, a.factors[5].covariance);
  EXPECT_EQ(b->factors[0].kind, SubmapFactorKind::kRegistration);
  EXPECT_EQ(b->factors[0].loss.type, RobustLossType::kHuber);
  EXPECT_EQ(b->factors[1].p_world_antenna, a.factors[1].p_world_antenna);
  EXPECT_EQ(b->factors[1].t_body_antenna, a.factors[1].t_body_antenna);
  EXPECT_EQ(b->factors[3].kind, SubmapFactorKind::kAttitudeChain);
  EXPECT_EQ(b->factors[3].transition, a.factors[3].transition);
  EXPECT_TRUE(b->factors[3].T_a.isApprox(a.factors[3].T_a, 1e-15));
  EXPECT_TRUE(b->factors[3].T.isApprox(a.factors[3].T, 1e-15));
  EXPECT_EQ(b->factors[3].covariance, a.factors[3].covariance);
  EXPECT_EQ(b->gnss_availability[1].availability, GnssAvailability::kOutage);
  // Write, read, write again: the same numbers (a pose's quaternion within its last digit).
  ASSERT_TRUE(WriteDriveResult(*b, dir / "two").ok());
  auto c = ReadDriveResult(dir / "two");
  ASSERT_TRUE(c.ok());
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_TRUE(c->submaps[k].T_world_submap.isApprox(a.submaps[k].T_world_submap, 1e-15));
    EXPECT_EQ(c->submaps[k].T_world_submap.translation(),
              a.submaps[k].T_world_submap.translation());
  }
  fs::remove_all(dir);
}

TEST(DriveResultIoTest, BadFilesAreNamed) {
  const fs::path dir = testing::MakeTempDir("drive_result_bad");
  auto missing = ReadDriveResult(dir / "nothing");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  ASSERT_TRUE(WriteDriveResult(Sample(), dir / "d").ok());
  const fs::path file = dir / "d" / kDriveResultFileName;
  const std::string good = Slurp(file);
  auto rewrite = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    const size_t at = s.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    s.replace(at, from.size(), to);
    std::ofstream(file, std::ios::binary | std::ios::trunc) << s;
  };
  auto expect = [&](const std::string& what) {
    auto r = ReadDriveResult(dir / "d");
    ASSERT_FALSE(r.ok()) << what;
    EXPECT_NE(r.status().message().find(what), std::string::npos) << r.status().ToString();
    EXPECT_NE(r.status().message().find(kDriveResultFileName), std::string::npos);
  };
  rewrite("\"version\": 1", "\"version\": 99");
  expect("version");
  rewrite("\"kind\": \"gnss\"", "\"kind\": \"magic\"");
  expect("factors[1].kind");
  rewrite("0.9200444146293233", "\"x\"");
  expect("factors[3].transition[0]: not a number");
  rewrite("\"transition\"", "\"transition_x\"");
  expect("factors[3]: missing transition");
  rewrite("\"gnss_bias_from\": 0", "\"gnss_bias_from\": -3");
  expect("factors[5].gnss_bias_from: must be a bias key >= 0");
  rewrite("0.9672161004820059", "1.5");
  expect("factors[5].transition: must be a number in [0, 1]");
  rewrite("\"scan_id\": 201", "\"scan_id\": \"x\"");
  expect("submaps[2].scans[1].scan_id");
  std::ofstream(file, std::ios::binary | std::ios::trunc) << good.substr(0, good.size() / 2);
  expect("parse");
  // A truncated cloud names the submap and the cloud file.
  std::ofstream(file, std::ios::binary | std::ios::trunc) << good;
  const fs::path cloud = dir / "d" / "submaps" / "000011_map.pcd";
  const std::string c = Slurp(cloud);
  std::ofstream(cloud, std::ios::binary | std::ios::trunc) << c.substr(0, c.size() - 40);
  expect("submaps[1].map_cloud");
  fs::remove_all(dir);
}

TEST(DriveResultIoTest, MapCloudsCanBeReadOneAtATime) {
  const testing::ScopedTempDir dir("drive_result_lazy");
  const DriveResult a = Sample();
  ASSERT_TRUE(WriteDriveResult(a, dir.path / "d").ok());
  DriveResultReadOptions lazy;
  lazy.map_clouds = false;
  auto b = ReadDriveResult(dir.path / "d", lazy);
  ASSERT_TRUE(b.ok()) << b.status().ToString();
  ASSERT_EQ(b->submaps.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_TRUE(b->submaps[k].map_cloud.empty());
    EXPECT_EQ(b->submaps[k].registration_cloud.size(), 25u);  // still read
    auto m = ReadDriveResultCloud(dir.path / "d", b->submaps[k].id, DriveResultCloud::kMap);
    ASSERT_TRUE(m.ok()) << m.status().ToString();
    EXPECT_EQ(m->points(), a.submaps[k].map_cloud.points());
    EXPECT_EQ(m->intensities(), a.submaps[k].map_cloud.intensities());
    auto r =
        ReadDriveResultCloud(dir.path / "d", b->submaps[k].id, DriveResultCloud::kRegistration);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->points(), a.submaps[k].registration_cloud.points());
  }
  // A missing map cloud is found by the lazy read too, naming the field and the file.
  fs::remove(dir.path / "d" / "submaps" / "000012_map.pcd");
  auto c = ReadDriveResult(dir.path / "d", lazy);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.status().code(), StatusCode::kNotFound);
  EXPECT_NE(c.status().message().find("submaps[2].map_cloud"), std::string::npos)
      << c.status().ToString();
  auto m = ReadDriveResultCloud(dir.path / "d", 12, DriveResultCloud::kMap);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("000012_map.pcd"), std::string::npos)
      << m.status().ToString();
}

}  // namespace
}  // namespace slam_mms
