// RosbagDriveReader on malformed bags (every failure a Status naming the bag, topic and message),
// its options and the NavSatFix status convention (split from rosbag_drive_reader_test.cpp).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sensor_msgs/NavSatStatus.h>

#include <fstream>

#include "rosbag/bag_test_util.hpp"
#include "rosbag/ros_conversions.hpp"
#include "slam_mms/rosbag/rosbag_drive_reader.hpp"
#include "slam_mms/rosbag/rosbag_writer.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// ---------------------------------------------------------------------------------------------
// Malformed bags: every failure is a Status naming the bag, topic and message.

class MalformedBag : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("rosbag_bad"); }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  // IMU at 100 Hz over [0, 1] s and 10 clouds at 10 Hz on `cloud_topics`.
  fs::path WriteGood(const std::string& name, const std::vector<std::string>& cloud_topics) {
    const fs::path bag = dir_ / name;
    testing::WriteTestBag(bag, [&](rosbag::Bag& b) {
      for (int k = 0; k <= 100; ++k) {
        const int64_t ns = testing::kBagT0Ns + k * 10000000LL;
        b.write("/imu", testing::RosTimeNs(ns), testing::TestImu(ns));
      }
      for (const std::string& topic : cloud_topics) {
        for (int s = 0; s < 10; ++s) {
          const int64_t ns = testing::kBagT0Ns + s * 100000000LL;
          b.write(topic, testing::RosTimeNs(ns), testing::SimpleCloud(ns, 500));
        }
      }
    });
    return bag;
  }
  fs::path dir_;
};

TEST_F(MalformedBag, MissingLidarTopicListsTheTopics) {
  const fs::path bag = WriteGood("no_lidar.bag", {});
  auto r = RosbagDriveReader::Open(bag, RosbagDriveReader::Options());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(r.status().message(), HasSubstr(bag.string()));
  EXPECT_THAT(r.status().message(), HasSubstr("no sensor_msgs/PointCloud2 topic"));
  EXPECT_THAT(r.status().message(), HasSubstr("/imu [sensor_msgs/Imu, 101 messages]"));

  RosbagDriveReader::Options o;
  o.lidar_topic = "/velodyne_points";
  r = RosbagDriveReader::Open(bag, o);
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(r.status().message(), HasSubstr("/velodyne_points (Options::lidar_topic) is not in"));
  o.lidar_topic = "/imu";
  r = RosbagDriveReader::Open(bag, o);
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(r.status().message(), HasSubstr("is sensor_msgs/Imu, not sensor_msgs/PointCloud2"));
}

TEST_F(MalformedBag, TwoCloudTopicsAreAmbiguousUntilOneIsChosen) {
  const fs::path bag = WriteGood("two_lidars.bag", {"/front/points", "/rear/points"});
  auto r = RosbagDriveReader::Open(bag, RosbagDriveReader::Options());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(r.status().message(),
              HasSubstr("2 sensor_msgs/PointCloud2 topics (/front/points, /rear/points)"));
  EXPECT_THAT(r.status().message(), HasSubstr("Options::lidar_topic"));
  RosbagDriveReader::Options o;
  o.lidar_topic = "/rear/points";
  r = RosbagDriveReader::Open(bag, o);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_EQ((*r)->lidar_topic(), "/rear/points");
  EXPECT_EQ((*r)->NumScans(), 10u);
  EXPECT_TRUE((*r)->ReadScan(9).ok());
  EXPECT_EQ((*r)->ReadScan(10).status().code(), StatusCode::kOutOfRange);
  EXPECT_FALSE((*r)->streams().initial_state.has_value());  // no orientation in the IMU
  EXPECT_TRUE((*r)->streams().gnss.empty());
}

TEST_F(MalformedBag, ImuTimeGoingBackwards) {
  const fs::path bag = dir_ / "imu_backwards.bag";
  testing::WriteTestBag(bag, [&](rosbag::Bag& b) {
    const int64_t stamps_ms[] = {0, 10, 20, 15, 30};
    for (int k = 0; k < 5; ++k) {
      const int64_t receipt = testing::kBagT0Ns + k * 10000000LL;  // receipt order is fine
      b.write("/imu", testing::RosTimeNs(receipt),
              testing::TestImu(testing::kBagT0Ns + stamps_ms[k] * 1000000LL));
    }
    b.write("/points", testing::RosTimeNs(testing::kBagT0Ns),
            testing::SimpleCloud(testing::kBagT0Ns, 100));
  });
  auto r = RosbagDriveReader::Open(bag, RosbagDriveReader::Options());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
  EXPECT_THAT(r.status().message(), HasSubstr(bag.string() + ": /imu message 3"));
  EXPECT_THAT(r.status().message(), HasSubstr("1317000000.015000000 is not after message 2's "
                                              "1317000000.020000000"));
}

TEST_F(MalformedBag, TruncatedCloudDataIsDataLossAtReadScan) {
  const fs::path bag = dir_ / "short_cloud.bag";
  testing::WriteTestBag(bag, [&](rosbag::Bag& b) {
    for (int k = 0; k <= 30; ++k) {
      const int64_t ns = testing::kBagT0Ns + k * 10000000LL;
      b.write("/imu", testing::RosTimeNs(ns), testing::TestImu(ns));
    }
    for (int s = 0; s < 3; ++s) {
      const int64_t ns = testing::kBagT0Ns + s * 100000000LL;
      sensor_msgs::PointCloud2 c = testing::SimpleCloud(ns, 500);
      if (s == 1) c.data.resize(c.data.size() / 2);
      b.write("/points", testing::RosTimeNs(ns), c);
    }
  });
  auto r = RosbagDriveReader::Open(bag, RosbagDriveReader::Options());
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  ASSERT_EQ((*r)->NumScans(), 3u);
  EXPECT_TRUE((*r)->ReadScan(0).ok());
  EXPECT_TRUE((*r)->ReadScan(2).ok());
  auto bad = (*r)->ReadScan(1);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kDataLoss);
  EXPECT_THAT(bad.status().message(), HasSubstr(bag.string() + ": /points message 1"));
  EXPECT_THAT(bad.status().message(), HasSubstr("field data has 4000 bytes"));
  EXPECT_THAT(bad.status().message(), HasSubstr("8000 (truncated)"));
}

TEST_F(MalformedBag, BigEndianCloudFailsOpen) {
  const fs::path bag = dir_ / "big_endian.bag";
  testing::WriteTestBag(bag, [&](rosbag::Bag& b) {
    b.write("/imu", testing::RosTimeNs(testing::kBagT0Ns), testing::TestImu(testing::kBagT0Ns));
    sensor_msgs::PointCloud2 c = testing::SimpleCloud(testing::kBagT0Ns, 10);
    c.is_bigendian = true;
    b.write("/points", testing::RosTimeNs(testing::kBagT0Ns), c);
  });
  auto r = RosbagDriveReader::Open(bag, RosbagDriveReader::Options());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
  EXPECT_THAT(r.status().message(), HasSubstr("/points message 0: is_bigendian"));
}

TEST_F(MalformedBag, TruncatedBagFileIsAStatusNamingTheFile) {
  const fs::path good = WriteGood("good.bag", {"/points"});
  std::ifstream in(good, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1000u);
  for (double fraction : {0.001, 0.1, 0.5, 0.9, 0.999}) {
    SCOPED_TRACE(fraction);
    const fs::path cut = dir_ / "cut.bag";
    std::ofstream(cut, std::ios::binary)
        .write(bytes.data(), static_cast<std::streamsize>(bytes.size() * fraction));
    auto r = RosbagDriveReader::Open(cut, RosbagDriveReader::Options());
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
    EXPECT_THAT(r.status().message(), HasSubstr(cut.string()));
    EXPECT_FALSE(RosbagDriveReader::ListTopics(cut).ok());
  }
  // Not a bag at all, and no file.
  const fs::path text = dir_ / "notes.bag";
  std::ofstream(text) << "not a bag\n";
  EXPECT_EQ(RosbagDriveReader::Open(text, RosbagDriveReader::Options()).status().code(),
            StatusCode::kDataLoss);
  EXPECT_EQ(
      RosbagDriveReader::Open(dir_ / "none.bag", RosbagDriveReader::Options()).status().code(),
      StatusCode::kNotFound);
}

TEST(RosbagOptions, ValidateNamesTheField) {
  RosbagDriveReader::Options o;
  EXPECT_TRUE(o.Validate().ok());
  o.first_scan = 5;
  o.last_scan = 2;
  EXPECT_THAT(o.Validate().message(), HasSubstr("last_scan = 2"));
  o = RosbagDriveReader::Options();
  o.scan_period_s = -1.0;
  EXPECT_THAT(o.Validate().message(), HasSubstr("scan_period_s"));
  o = RosbagDriveReader::Options();
  o.T_body_lidar.linear() *= 2.0;
  EXPECT_THAT(o.Validate().message(), HasSubstr("T_body_lidar"));
  RosbagWriteOptions w;
  EXPECT_TRUE(w.Validate().ok());
  w.gnss_topic = w.imu_topic;
  EXPECT_THAT(w.Validate().message(), HasSubstr("given for two streams"));
}

TEST(RosbagFixTypeConvention, StatusAndSigma) {
  using sensor_msgs::NavSatStatus;
  EXPECT_EQ(RosbagFixType(NavSatStatus::STATUS_NO_FIX, 0.01), GnssFixType::kNone);
  EXPECT_EQ(RosbagFixType(NavSatStatus::STATUS_FIX, 0.01), GnssFixType::kSingle);
  EXPECT_EQ(RosbagFixType(NavSatStatus::STATUS_SBAS_FIX, 0.01), GnssFixType::kDifferential);
  EXPECT_EQ(RosbagFixType(NavSatStatus::STATUS_GBAS_FIX, 0.05), GnssFixType::kRtkFixed);
  EXPECT_EQ(RosbagFixType(NavSatStatus::STATUS_GBAS_FIX, 0.0500001), GnssFixType::kRtkFloat);
  EXPECT_EQ(RosbagFixType(NavSatStatus::STATUS_GBAS_FIX, 0.2, 0.25), GnssFixType::kRtkFixed);
  EXPECT_EQ(RosbagFixType(7, 0.01), GnssFixType::kNone);
  // Sigmas: sqrt((c0 + c4) / 2), sqrt(c8); unknown covariance -> the defaults.
  sensor_msgs::NavSatFix fix;
  fix.position_covariance = {0.01, 0, 0, 0, 0.04, 0, 0, 0, 0.09};
  fix.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN;
  double sh = 0.0, sv = 0.0;
  rosbag_internal::NavSatFixSigmas(fix, 1.0, 1.5, &sh, &sv);
  EXPECT_DOUBLE_EQ(sh, std::sqrt(0.025));
  EXPECT_DOUBLE_EQ(sv, 0.3);
  fix.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_UNKNOWN;
  rosbag_internal::NavSatFixSigmas(fix, 1.0, 1.5, &sh, &sv);
  EXPECT_EQ(sh, 1.0);
  EXPECT_EQ(sv, 1.5);
}

}  // namespace
}  // namespace slam_mms
