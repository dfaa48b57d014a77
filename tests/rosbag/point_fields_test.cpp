// RosbagDriveReader on the PointCloud2 layouts drivers write: Velodyne (`time` float32 relative,
// packed 22-byte points), Ouster (`t` uint32 ns relative, organized, padded rows), Hesai
// (`timestamp` float64 absolute), float64 coordinates with a uint8 intensity and no time field,
// a driver stamping the scan end (negative times), and bad layouts.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "rosbag/bag_test_util.hpp"
#include "slam_mms/rosbag/rosbag_drive_reader.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using sensor_msgs::PointField;
using ::testing::HasSubstr;
using testing::Put;

class PointFields : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("rosbag_fields"); }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  // A bag with one IMU message and the given clouds on /points (receipt time = header stamp).
  fs::path Bag(const std::vector<sensor_msgs::PointCloud2>& clouds) {
    const fs::path bag = dir_ / ("b" + std::to_string(count_++) + ".bag");
    testing::WriteTestBag(bag, [&](rosbag::Bag& b) {
      b.write("/imu", testing::RosTimeNs(testing::kBagT0Ns), testing::TestImu(testing::kBagT0Ns));
      for (const auto& c : clouds) b.write("/points", c.header.stamp, c);
    });
    return bag;
  }
  static std::unique_ptr<RosbagDriveReader> Open(const fs::path& bag,
                                                 const RosbagDriveReader::Options& o = {}) {
    auto r = RosbagDriveReader::Open(bag, o);
    EXPECT_TRUE(r.ok()) << r.status().ToString();
    return r.ok() ? std::move(r).value() : nullptr;
  }
  fs::path dir_;
  int count_ = 0;
};

TEST_F(PointFields, VelodyneTimeFloat32Relative) {
  constexpr uint32_t kN = 360;
  const int64_t stamp = testing::kBagT0Ns + 5;
  const auto cloud = testing::TestCloud(stamp,
                                        {{"x", 0, PointField::FLOAT32},
                                         {"y", 4, PointField::FLOAT32},
                                         {"z", 8, PointField::FLOAT32},
                                         {"intensity", 12, PointField::FLOAT32},
                                         {"ring", 16, PointField::UINT16},
                                         {"time", 18, PointField::FLOAT32}},
                                        22, kN, 1, [](size_t k, uint8_t* p) {
                                          Put<float>(p, 0, 1.0f + k);
                                          Put<float>(p, 4, -2.0f);
                                          Put<float>(p, 8, 0.25f * k);
                                          Put<float>(p, 12, 7.0f);
                                          Put<uint16_t>(p, 16, static_cast<uint16_t>(k % 32));
                                          Put<float>(p, 18, static_cast<float>(k * (0.1 / kN)));
                                        });
  auto r = Open(Bag({cloud}));
  ASSERT_NE(r, nullptr);
  EXPECT_TRUE(r->ScanHasTimeField(0));
  EXPECT_EQ(r->ScanStart(0).nanoseconds(), stamp);
  const float max_t = static_cast<float>((kN - 1) * (0.1 / kN));
  EXPECT_EQ(r->ScanEnd(0).nanoseconds(), stamp + std::llround(static_cast<double>(max_t) * 1e9));
  auto scan = r->ReadScan(0);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  ASSERT_EQ(scan->cloud.size(), kN);
  for (uint32_t k = 0; k < kN; ++k) {
    EXPECT_EQ(scan->cloud.points()[k], Eigen::Vector3f(1.0f + k, -2.0f, 0.25f * k));
    EXPECT_EQ(scan->cloud.intensities()[k], 7.0f);
    EXPECT_EQ(scan->cloud.time_offsets_s()[k], static_cast<float>(k * (0.1 / kN)));
  }
}

TEST_F(PointFields, OusterTUint32NanosecondsOrganizedWithRowPadding) {
  constexpr uint32_t kW = 8, kH = 4;
  const int64_t stamp = testing::kBagT0Ns + 123456789;
  const auto cloud = testing::TestCloud(
      stamp,
      {{"x", 0, PointField::FLOAT32},
       {"y", 4, PointField::FLOAT32},
       {"z", 8, PointField::FLOAT32},
       {"intensity", 16, PointField::FLOAT32},
       {"t", 20, PointField::UINT32},
       {"reflectivity", 24, PointField::UINT16},
       {"ring", 26, PointField::UINT16},
       {"ambient", 28, PointField::UINT16},
       {"range", 32, PointField::UINT32}},
      48, kW, kH,
      [](size_t k, uint8_t* p) {
        const uint32_t col = k % kW;
        Put<float>(p, 0, 3.0f);
        Put<float>(p, 4, static_cast<float>(k));
        Put<float>(p, 8, 0.0f);
        Put<float>(p, 16, 100.0f + k);
        Put<uint32_t>(p, 20, col * 12500000u);  // 12.5 ms per column
      },
      /*row_padding=*/16);
  auto r = Open(Bag({cloud}));
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->ScanStart(0).nanoseconds(), stamp);
  EXPECT_EQ(r->ScanEnd(0).nanoseconds(), stamp + 7 * 12500000LL);
  auto scan = r->ReadScan(0);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  ASSERT_EQ(scan->cloud.size(), kW * kH);
  for (size_t k = 0; k < kW * kH; ++k) {
    EXPECT_EQ(scan->cloud.points()[k].y(), static_cast<float>(k));
    EXPECT_EQ(scan->cloud.intensities()[k], 100.0f + k);
    EXPECT_EQ(scan->cloud.time_offsets_s()[k], static_cast<float>((k % kW) * 12500000 * 1e-9));
  }
}

TEST_F(PointFields, HesaiTimestampFloat64Absolute) {
  constexpr uint32_t kN = 100;
  const int64_t stamp = testing::kBagT0Ns + 500000000;  // .5 s
  const double stamp_s = 1317000000.5;
  const auto cloud = testing::TestCloud(stamp,
                                        {{"x", 0, PointField::FLOAT32},
                                         {"y", 4, PointField::FLOAT32},
                                         {"z", 8, PointField::FLOAT32},
                                         {"intensity", 12, PointField::FLOAT32},
                                         {"timestamp", 16, PointField::FLOAT64},
                                         {"ring", 24, PointField::UINT16}},
                                        32, kN, 1, [&](size_t k, uint8_t* p) {
                                          Put<float>(p, 0, 5.0f);
                                          Put<float>(p, 4, 1.0f);
                                          Put<float>(p, 8, 0.0f);
                                          Put<float>(p, 12, 1.0f);
                                          Put<double>(p, 16, stamp_s + 1e-3 * k);
                                        });
  const fs::path bag = Bag({cloud});
  auto r = Open(bag);  // kAuto: 1.3e9 s > 1e6 s -> absolute
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->ScanStart(0).nanoseconds(), stamp);
  EXPECT_NEAR(r->ScanEnd(0).SecondsSince(r->ScanStart(0)), 0.099, 1e-6);
  auto scan = r->ReadScan(0);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  for (size_t k = 0; k < kN; ++k) EXPECT_NEAR(scan->cloud.time_offsets_s()[k], 1e-3 * k, 1e-6);

  // The same cloud declared relative: times 1.3e9 s from the stamp are refused at ReadScan.
  RosbagDriveReader::Options o;
  o.time_field = RosbagDriveReader::TimeField::kRelativeToHeader;
  auto wrong = Open(bag, o);
  ASSERT_NE(wrong, nullptr);
  const auto bad = wrong->ReadScan(0);
  EXPECT_EQ(bad.status().code(), StatusCode::kDataLoss);
  EXPECT_THAT(bad.status().message(), HasSubstr("/points message 0: field 'timestamp'"));
  EXPECT_THAT(bad.status().message(), HasSubstr("Options::time_field"));
}

TEST_F(PointFields, DriverStampingTheScanEndWithNegativeTimes) {
  constexpr uint32_t kN = 101;
  const int64_t stamp = testing::kBagT0Ns + 100000000;
  const auto cloud =
      testing::TestCloud(stamp,
                         {{"x", 0, PointField::FLOAT32},
                          {"y", 4, PointField::FLOAT32},
                          {"z", 8, PointField::FLOAT32},
                          {"time", 12, PointField::FLOAT32}},
                         16, kN, 1, [](size_t k, uint8_t* p) {
                           Put<float>(p, 0, 1.0f);
                           Put<float>(p, 4, 0.0f);
                           Put<float>(p, 8, 0.0f);
                           Put<float>(p, 12, static_cast<float>(-0.1 + 1e-3 * k));  // [-0.1, 0]
                         });
  auto r = Open(Bag({cloud}));
  ASSERT_NE(r, nullptr);
  EXPECT_NEAR(r->ScanStart(0).SecondsSince(Timestamp::FromNanoseconds(stamp)), -0.1, 1e-8);
  EXPECT_NEAR(r->ScanEnd(0).SecondsSince(Timestamp::FromNanoseconds(stamp)), 0.0, 1e-8);
  auto scan = r->ReadScan(0);
  ASSERT_TRUE(scan.ok());
  for (size_t k = 0; k < kN; ++k) EXPECT_NEAR(scan->cloud.time_offsets_s()[k], 1e-3 * k, 1e-6);
  EXPECT_EQ(scan->cloud.intensities()[0], 0.0f);  // no intensity field
}

TEST_F(PointFields, Float64CoordinatesUint8IntensityNoTimeHeaderAtScanEnd) {
  std::vector<sensor_msgs::PointCloud2> clouds;
  for (int s = 0; s < 3; ++s) {
    clouds.push_back(testing::TestCloud(
        testing::kBagT0Ns + s * 50000000LL,  // 20 Hz
        {{"x", 0, PointField::FLOAT64},
         {"y", 8, PointField::FLOAT64},
         {"z", 16, PointField::FLOAT64},
         {"reflectance", 24, PointField::UINT8}},
        25, 4, 1, [](size_t k, uint8_t* p) {
          Put<double>(p, 0, k == 2 ? std::numeric_limits<double>::quiet_NaN() : 0.0);
          Put<double>(p, 8, k == 1 ? 2.0 : -2.0);  // azimuth +90 / -90 deg
          Put<double>(p, 16, 1.5);
          Put<uint8_t>(p, 24, static_cast<uint8_t>(200 + k));
        }));
  }
  RosbagDriveReader::Options o;
  o.header_stamp = RosbagDriveReader::HeaderStamp::kScanEnd;
  auto r = Open(Bag(clouds), o);
  ASSERT_NE(r, nullptr);
  EXPECT_FALSE(r->ScanHasTimeField(1));
  EXPECT_EQ(r->ScanStart(1).nanoseconds(), testing::kBagT0Ns);  // header - median 50 ms
  EXPECT_EQ(r->ScanEnd(1).nanoseconds(), testing::kBagT0Ns + 50000000LL);
  auto scan = r->ReadScan(1);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  ASSERT_EQ(scan->cloud.size(), 3u);  // the NaN point dropped
  EXPECT_EQ(r->TotalDroppedPoints(), 1u);
  EXPECT_EQ(scan->cloud.points()[1], Eigen::Vector3f(0.0f, 2.0f, 1.5f));
  EXPECT_EQ(scan->cloud.intensities()[1], 201.0f);
  // Clockwise: +90 deg azimuth is a quarter of the way, -90 deg three quarters.
  EXPECT_NEAR(scan->cloud.time_offsets_s()[1], 0.25 * 0.05, 1e-6);
  EXPECT_NEAR(scan->cloud.time_offsets_s()[0], 0.75 * 0.05, 1e-6);
}

TEST_F(PointFields, BadLayoutsFailOpenNamingTheField) {
  const auto layout = [](std::vector<testing::TestField> fields, uint32_t step) {
    return testing::TestCloud(testing::kBagT0Ns, fields, step, 2, 1, [](size_t, uint8_t*) {});
  };
  struct Case {
    sensor_msgs::PointCloud2 cloud;
    const char* expected;
  };
  const Case cases[] = {
      {layout({{"y", 0, PointField::FLOAT32}, {"z", 4, PointField::FLOAT32}}, 8), "no field 'x'"},
      {layout({{"x", 0, PointField::FLOAT32},
               {"y", 4, PointField::FLOAT32},
               {"z", 8, PointField::INT16}},
              12),
       "field 'z' is int16; float32 or float64 required"},
      {layout({{"x", 0, PointField::FLOAT32},
               {"y", 4, PointField::FLOAT32},
               {"z", 8, PointField::FLOAT64}},
              12),
       "field 'z' (offset 8, float64) lies outside point_step 12"},
      {layout({{"x", 0, PointField::FLOAT32},
               {"y", 4, PointField::FLOAT32},
               {"z", 8, PointField::FLOAT32},
               {"time", 12, 42}},
              16),
       "field 'time' has unknown datatype 42"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.expected);
    auto r = RosbagDriveReader::Open(Bag({c.cloud}), RosbagDriveReader::Options());
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
    EXPECT_THAT(r.status().message(), HasSubstr("/points message 0: "));
    EXPECT_THAT(r.status().message(), HasSubstr(c.expected));
  }
  // An empty cloud is indexed but unreadable.
  auto empty = testing::SimpleCloud(testing::kBagT0Ns, 0);
  auto r = Open(Bag({empty}));
  ASSERT_NE(r, nullptr);
  EXPECT_THAT(r->ReadScan(0).status().message(), HasSubstr("contains no points"));
}

}  // namespace
}  // namespace slam_mms
