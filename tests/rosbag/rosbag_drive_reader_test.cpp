// RosbagDriveReader / WriteRosbag: (a) round trips of a simulated drive and of the real KITTI
// frames (KittiDriveReader -> WriteRosbag -> RosbagDriveReader), (b) a kitti2bag-style bag written
// independently by python3-rosbag. Malformed bags: rosbag_malformed_test.cpp.
#include "slam_mms/rosbag/rosbag_drive_reader.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sensor_msgs/NavSatStatus.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "rosbag/bag_test_util.hpp"
#include "rosbag/ros_conversions.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/rosbag/rosbag_writer.hpp"
#include "testing/simulated_drive.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// ---------------------------------------------------------------------------------------------
// (a) Round trip.

struct RoundTripTolerances {
  double time_offset_s = 1e-6;  // float32 seconds
  double scan_end_s = 1e-3;     // end = start + max per-point time (not the file's end)
};

// Everything the bag carries must come back: scans bitwise (times within float32), streams
// bitwise, sigmas within 1e-12, fix types through RosbagFixType, the initial state within 1e-9.
void ExpectSameDrive(const DriveReader& in, const RosbagDriveReader& out) {
  ASSERT_EQ(in.NumScans(), out.NumScans());
  for (size_t i = 0; i < in.NumScans(); ++i) {
    SCOPED_TRACE("scan " + std::to_string(i));
    EXPECT_EQ(in.ScanStart(i), out.ScanStart(i));
    EXPECT_NEAR(out.ScanEnd(i).SecondsSince(in.ScanEnd(i)), 0.0, RoundTripTolerances().scan_end_s);
    EXPECT_LE(out.ScanEnd(i), in.ScanEnd(i).PlusSeconds(1e-6));
    auto a = in.ReadScan(i);
    auto b = out.ReadScan(i);
    ASSERT_TRUE(a.ok()) << a.status().ToString();
    ASSERT_TRUE(b.ok()) << b.status().ToString();
    EXPECT_EQ(a->index, b->index);
    EXPECT_EQ(b->stamp_start, a->stamp_start);
    ASSERT_EQ(a->cloud.size(), b->cloud.size());
    EXPECT_TRUE(a->cloud.points() == b->cloud.points());
    EXPECT_TRUE(a->cloud.intensities() == b->cloud.intensities());
    double max_dt = 0.0;
    for (size_t k = 0; k < a->cloud.size(); ++k) {
      max_dt = std::max(max_dt, static_cast<double>(std::abs(a->cloud.time_offsets_s()[k] -
                                                             b->cloud.time_offsets_s()[k])));
    }
    EXPECT_LE(max_dt, RoundTripTolerances().time_offset_s);
    EXPECT_THAT(b->source, HasSubstr(out.lidar_topic() + " message " + std::to_string(i)));
  }
  const DriveStreams& s = in.streams();
  const DriveStreams& t = out.streams();
  ASSERT_EQ(s.imu.size(), t.imu.size());
  for (size_t k = 0; k < s.imu.size(); ++k) {
    ASSERT_EQ(s.imu[k].stamp, t.imu[k].stamp) << k;
    ASSERT_EQ(s.imu[k].accel_mps2, t.imu[k].accel_mps2) << k;
    ASSERT_EQ(s.imu[k].gyro_radps, t.imu[k].gyro_radps) << k;
  }
  ASSERT_EQ(t.imu_source.size(), t.imu.size());
  ASSERT_EQ(s.gnss.size(), t.gnss.size());
  for (size_t k = 0; k < s.gnss.size(); ++k) {
    const GnssFix& f = s.gnss[k];
    const GnssFix& g = t.gnss[k];
    ASSERT_EQ(f.stamp, g.stamp) << k;
    ASSERT_EQ(f.latitude_deg, g.latitude_deg) << k;
    ASSERT_EQ(f.longitude_deg, g.longitude_deg) << k;
    ASSERT_EQ(f.height_m, g.height_m) << k;
    ASSERT_NEAR(f.sigma_horizontal_m, g.sigma_horizontal_m, 1e-12) << k;
    ASSERT_NEAR(f.sigma_vertical_m, g.sigma_vertical_m, 1e-12) << k;
    ASSERT_EQ(g.type, RosbagFixType(rosbag_internal::NavSatStatusFor(f.type), f.sigma_horizontal_m))
        << k;
  }
  ASSERT_EQ(s.initial_state.has_value(), t.initial_state.has_value());
  if (s.initial_state) {
    EXPECT_EQ(s.initial_state->stamp, t.initial_state->stamp);
    EXPECT_TRUE(s.initial_state->T_world_body.linear().isApprox(
        t.initial_state->T_world_body.linear(), 1e-9));
    EXPECT_LE((s.initial_state->v_world_mps - t.initial_state->v_world_mps).norm(), 1e-9);
  }
  // The attitude's stated sigmas travel as orientation_covariance's diagonal.
  ASSERT_EQ(s.initial_attitude_sigma_rpy_rad.has_value(),
            t.initial_attitude_sigma_rpy_rad.has_value());
  if (s.initial_attitude_sigma_rpy_rad) {
    EXPECT_TRUE(
        s.initial_attitude_sigma_rpy_rad->isApprox(*t.initial_attitude_sigma_rpy_rad, 1e-12));
  }
  EXPECT_TRUE(t.T_body_lidar.isApprox(s.T_body_lidar, 0.0));
}

RosbagDriveReader::Options OptionsFor(const DriveReader& in) {
  RosbagDriveReader::Options o;
  o.T_body_lidar = in.streams().T_body_lidar;
  return o;
}

constexpr const char* kNoPythonRosbag =
    "python3-rosbag / python3-sensor-msgs / python3-geometry-msgs not installed "
    "(scripts/install_deps.sh)";

bool PythonRosbagAvailable() {
  return std::system(
             "/usr/bin/python3 -c 'import rosbag, sensor_msgs.msg, geometry_msgs.msg' "
             ">/dev/null 2>&1") == 0;
}

// Runs `cmd` and files each output line under its first word; false when it fails.
bool RunAndCollect(const std::string& cmd, std::map<std::string, std::vector<std::string>>* out) {
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) return false;
  char buf[4096];
  while (std::fgets(buf, sizeof(buf), pipe) != nullptr) {
    std::string line(buf);
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    const size_t sp = line.find(' ');
    (*out)[line.substr(0, sp)].push_back(sp == std::string::npos ? "" : line.substr(sp + 1));
  }
  return ::pclose(pipe) == 0;
}

// A 3 s simulated drive (30 HDL-64 scans, 100 Hz IMU, RTK GNSS), once per test process.
class SimulatedRoundTrip : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto drive = testing::SimulateDrive("slam_mms_rosbag_roundtrip", /*seed=*/7, 3.0);
    ASSERT_TRUE(drive.ok()) << drive.status().ToString();
    sim_ = new testing::SimulatedDrive(std::move(drive).value());
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    if (sim_ != nullptr) fs::remove_all(sim_->dir, ec);
    delete sim_;
    sim_ = nullptr;
  }
  void SetUp() override {
    ASSERT_NE(sim_, nullptr);
    auto kitti = KittiDriveReader::Open(sim_->drive_dir, KittiRawReader::Options());
    ASSERT_TRUE(kitti.ok()) << kitti.status().ToString();
    kitti_ = std::move(kitti).value();
    dir_ = testing::MakeTempDir("rosbag_rt");
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  static testing::SimulatedDrive* sim_;
  std::unique_ptr<KittiDriveReader> kitti_;
  fs::path dir_;
};
testing::SimulatedDrive* SimulatedRoundTrip::sim_ = nullptr;

TEST_F(SimulatedRoundTrip, SameDriveAsKittiRaw) {
  ASSERT_GE(kitti_->NumScans(), 25u);             // 3 s at 10 Hz
  ASSERT_GE(kitti_->streams().imu.size(), 250u);  // 100 Hz
  const fs::path bag = dir_ / "sim.bag";
  ASSERT_TRUE(WriteRosbag(*kitti_, bag, RosbagWriteOptions()).ok());
  auto reader = RosbagDriveReader::Open(bag, OptionsFor(*kitti_));
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->lidar_topic(), "/velodyne_points");
  EXPECT_EQ((*reader)->imu_topic(), "/imu/data");
  EXPECT_EQ((*reader)->gnss_topic(), "/gps/fix");
  EXPECT_EQ((*reader)->velocity_topic(), "/gps/vel");
  EXPECT_TRUE((*reader)->ScanHasTimeField(0));
  ExpectSameDrive(*kitti_, **reader);

  // The simulator's fix types (GnssSimulator: RTK fixed, nominal 0.015 m x a log-normal factor;
  // float 0.25 m; SPS 1.5 m; none during outages) come back unchanged: its fixed sigmas stay at
  // or below 0.05 m and its float ones above, so the GBAS split of RosbagFixType restores them.
  std::map<GnssFixType, int> census;
  const auto& in = kitti_->streams().gnss;
  const auto& out = (*reader)->streams().gnss;
  for (size_t k = 0; k < in.size(); ++k) {
    ++census[in[k].type];
    EXPECT_EQ(in[k].type, out[k].type) << k << " sigma " << in[k].sigma_horizontal_m;
  }
  EXPECT_GT(census[GnssFixType::kRtkFixed], 0);
  for (auto [type, count] : census) {
    RecordProperty(std::string("fixes_") + GnssFixTypeName(type), count);
  }
}

TEST_F(SimulatedRoundTrip, WithoutTimeFieldTimesComeFromTheAzimuth) {
  const fs::path bag = dir_ / "sim_notime.bag";
  RosbagWriteOptions w;
  w.write_point_time = false;
  w.compression = RosbagWriteOptions::Compression::kLz4;
  ASSERT_TRUE(WriteRosbag(*kitti_, bag, w).ok());
  for (auto stamp :
       {RosbagDriveReader::HeaderStamp::kScanStart, RosbagDriveReader::HeaderStamp::kScanEnd}) {
    RosbagDriveReader::Options o = OptionsFor(*kitti_);
    o.header_stamp = stamp;
    o.first_scan = 2;
    o.last_scan = 6;
    auto reader = RosbagDriveReader::Open(bag, o);
    ASSERT_TRUE(reader.ok()) << reader.status().ToString();
    const RosbagDriveReader& r = **reader;
    ASSERT_EQ(r.NumScans(), 5u);
    EXPECT_FALSE(r.ScanHasTimeField(0));
    // Median spacing of the header stamps (= the KITTI scan starts) of scans 2..6.
    std::vector<int64_t> gaps;
    for (size_t i = 3; i <= 6; ++i) {
      gaps.push_back(kitti_->ScanStart(i).nanoseconds() - kitti_->ScanStart(i - 1).nanoseconds());
    }
    std::sort(gaps.begin(), gaps.end());
    const int64_t period_ns = gaps[2];
    for (size_t i = 0; i < r.NumScans(); ++i) {
      const Timestamp header = kitti_->ScanStart(i + 2);
      const bool at_start = stamp == RosbagDriveReader::HeaderStamp::kScanStart;
      EXPECT_EQ(r.ScanStart(i).nanoseconds(), header.nanoseconds() - (at_start ? 0 : period_ns));
      EXPECT_EQ(r.ScanEnd(i).nanoseconds() - r.ScanStart(i).nanoseconds(), period_ns);
      auto a = kitti_->ReadScan(i + 2);
      auto b = r.ReadScan(i);
      ASSERT_TRUE(a.ok() && b.ok());
      EXPECT_EQ(b->index, static_cast<int64_t>(i + 2));
      ASSERT_EQ(a->cloud.size(), b->cloud.size());
      EXPECT_TRUE(a->cloud.points() == b->cloud.points());
      EXPECT_TRUE(a->cloud.intensities() == b->cloud.intensities());
      for (size_t k = 0; k < b->cloud.size(); k += 97) {
        const Eigen::Vector3f& p = b->cloud.points()[k];
        EXPECT_NEAR(
            b->cloud.time_offsets_s()[k],
            KittiAzimuthFraction(p.x(), p.y(), SpinDirection::kClockwise) * period_ns * 1e-9, 1e-6);
      }
    }
  }
}

TEST_F(SimulatedRoundTrip, ConcurrentReadScanMatchesSequential) {
  const fs::path bag = dir_ / "sim.bag";
  ASSERT_TRUE(WriteRosbag(*kitti_, bag, RosbagWriteOptions()).ok());
  auto reader = RosbagDriveReader::Open(bag, OptionsFor(*kitti_));
  ASSERT_TRUE(reader.ok());
  const RosbagDriveReader& r = **reader;
  std::vector<size_t> sizes(r.NumScans(), 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 3; ++t) {
    threads.emplace_back([&, t] {
      for (size_t i = t; i < r.NumScans(); i += 3) {
        auto s = r.ReadScan(i);
        if (s.ok()) sizes[i] = s->cloud.size();
      }
    });
  }
  for (auto& th : threads) th.join();
  for (size_t i = 0; i < r.NumScans(); ++i) {
    auto s = kitti_->ReadScan(i);
    ASSERT_TRUE(s.ok());
    EXPECT_EQ(sizes[i], s->cloud.size()) << i;
  }
}

// The bag WriteRosbag writes, read by python3-rosbag (tests/rosbag/summarize_bag.py).
TEST_F(SimulatedRoundTrip, PythonRosbagReadsTheWrittenBag) {
  if (!PythonRosbagAvailable()) GTEST_SKIP() << kNoPythonRosbag;
  const fs::path bag = dir_ / "sim.bag";
  ASSERT_TRUE(WriteRosbag(*kitti_, bag, RosbagWriteOptions()).ok());
  const fs::path script = fs::path(__FILE__).parent_path() / "summarize_bag.py";
  std::map<std::string, std::vector<std::string>> lines;  // key -> the rest of its line(s)
  ASSERT_TRUE(RunAndCollect("/usr/bin/python3 " + script.string() + " " + bag.string(), &lines));
  const DriveStreams& s = kitti_->streams();
  EXPECT_THAT(lines["topic"],
              ::testing::UnorderedElementsAre(
                  "/velodyne_points sensor_msgs/PointCloud2 " + std::to_string(kitti_->NumScans()),
                  "/imu/data sensor_msgs/Imu " + std::to_string(s.imu.size()),
                  "/gps/fix sensor_msgs/NavSatFix " + std::to_string(s.gnss.size()),
                  "/gps/vel geometry_msgs/TwistStamped 1"));
  EXPECT_EQ(lines["cloud_fields"].at(0), "x:0:7,y:4:7,z:8:7,intensity:12:7,time:16:7");
  auto scan = kitti_->ReadScan(0);
  ASSERT_TRUE(scan.ok());
  std::istringstream p0(lines["cloud_point0"].at(0));
  double x, y, z, i, t;
  p0 >> x >> y >> z >> i >> t;
  EXPECT_EQ(Eigen::Vector3f(x, y, z), scan->cloud.points()[0]);
  EXPECT_EQ(static_cast<float>(i), scan->cloud.intensities()[0]);
  EXPECT_EQ(static_cast<float>(t), scan->cloud.time_offsets_s()[0]);
  const int64_t ns = kitti_->ScanStart(0).nanoseconds();
  EXPECT_EQ(lines["cloud_stamp0"].at(0),
            std::to_string(ns / 1000000000) + " " + std::to_string(ns % 1000000000));
  // The attitude is on the IMU message at the initial state's stamp (the first here).
  ASSERT_TRUE(s.initial_state.has_value());
  ASSERT_EQ(s.initial_state->stamp, s.imu.front().stamp);
  // Its covariance: the stated roll sigma squared (a KITTI record: 0.03 deg); the next: none.
  ASSERT_TRUE(s.initial_attitude_sigma_rpy_rad.has_value());
  std::istringstream cov_line(lines["imu_orientation_cov0"].at(0));
  double cov0 = 0.0, cov1 = 0.0;
  cov_line >> cov0 >> cov1;
  EXPECT_DOUBLE_EQ(cov0, std::pow((*s.initial_attitude_sigma_rpy_rad)(0), 2));
  EXPECT_EQ(cov1, -1.0);
  std::istringstream f0(lines["fix0"].at(0));
  int status = 0, cov_type = 0;
  double lat, lon, alt, c0, c8;
  f0 >> status >> lat >> lon >> alt >> c0 >> c8 >> cov_type;
  const GnssFix& fix = s.gnss.front();
  EXPECT_EQ(status, rosbag_internal::NavSatStatusFor(fix.type));
  EXPECT_EQ(lat, fix.latitude_deg);
  EXPECT_EQ(lon, fix.longitude_deg);
  EXPECT_EQ(alt, fix.height_m);
  EXPECT_EQ(c0, fix.sigma_horizontal_m * fix.sigma_horizontal_m);
  EXPECT_EQ(c8, fix.sigma_vertical_m * fix.sigma_vertical_m);
  EXPECT_EQ(cov_type, 2);  // COVARIANCE_TYPE_DIAGONAL_KNOWN
  std::istringstream v0(lines["vel0"].at(0));
  std::string frame;
  double vx, vy, vz;
  v0 >> frame >> vx >> vy >> vz;
  EXPECT_EQ(frame, "enu");
  EXPECT_EQ(Eigen::Vector3d(vx, vy, vz), s.initial_state->v_world_mps);
}

TEST(RosbagRoundTrip, RealKittiFrames) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  KittiRawReader::Options ko;
  ko.last_frame = 9;
  auto kitti = KittiDriveReader::Open(testing::KittiRawDriveDir(), ko);
  ASSERT_TRUE(kitti.ok()) << kitti.status().ToString();
  const fs::path dir = testing::MakeTempDir("rosbag_kitti");
  const fs::path bag = dir / "kitti.bag";
  ASSERT_TRUE(WriteRosbag(**kitti, bag, RosbagWriteOptions()).ok());
  auto reader = RosbagDriveReader::Open(bag, OptionsFor(**kitti));
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  ExpectSameDrive(**kitti, **reader);
  // Drive 0013's OXTS reports differential fixes (posmode 4) -> STATUS_SBAS_FIX -> the same type.
  for (const GnssFix& f : (*reader)->streams().gnss) EXPECT_EQ(f.type, GnssFixType::kDifferential);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// ---------------------------------------------------------------------------------------------
// (b) An independent writer: python3-rosbag, kitti2bag's topics and conventions.

struct KittiStyleBag {
  static constexpr int kPoints = 1000;
  static constexpr int kScans = 5;
  static constexpr int kOxts = 10;
};

TEST(RosbagPythonBag, Kitti2bagStyleTopicsAreFoundAndRead) {
  const fs::path script = fs::path(__FILE__).parent_path() / "write_kitti2bag_style_bag.py";
  if (!PythonRosbagAvailable()) GTEST_SKIP() << kNoPythonRosbag;
  const fs::path dir = testing::MakeTempDir("rosbag_py");
  const fs::path bag = dir / "kitti2bag_style.bag";
  const std::string cmd = "/usr/bin/python3 " + script.string() + " " + bag.string();
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;

  auto reader = RosbagDriveReader::Open(bag, RosbagDriveReader::Options());
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  const RosbagDriveReader& r = **reader;
  EXPECT_EQ(r.lidar_topic(), "/kitti/velo/pointcloud");
  EXPECT_EQ(r.imu_topic(), "/kitti/oxts/imu");
  EXPECT_EQ(r.gnss_topic(), "/kitti/oxts/gps/fix");
  EXPECT_EQ(r.velocity_topic(), "/kitti/oxts/gps/vel");

  const int64_t t0 = testing::kBagT0Ns;
  ASSERT_EQ(r.NumScans(), static_cast<size_t>(KittiStyleBag::kScans));
  for (int s = 0; s < KittiStyleBag::kScans; ++s) {
    SCOPED_TRACE("scan " + std::to_string(s));
    EXPECT_EQ(r.ScanStart(s).nanoseconds(), t0 + 100000000LL * (s + 1));
    EXPECT_EQ(r.ScanEnd(s).nanoseconds(), t0 + 100000000LL * (s + 2));  // median spacing 0.1 s
    auto scan = r.ReadScan(s);
    ASSERT_TRUE(scan.ok()) << scan.status().ToString();
    EXPECT_EQ(scan->index, s);
    ASSERT_EQ(scan->cloud.size(), static_cast<size_t>(KittiStyleBag::kPoints));
    for (int k = 0; k < KittiStyleBag::kPoints; ++k) {
      const double a = 2.0 * M_PI * k / KittiStyleBag::kPoints;
      const Eigen::Vector3f p(static_cast<float>((10.0 + s) * std::cos(a)),
                              static_cast<float>((10.0 + s) * std::sin(a)),
                              static_cast<float>(0.01 * k - 1.0));
      ASSERT_EQ(scan->cloud.points()[k], p) << k;
      ASSERT_EQ(scan->cloud.intensities()[k],
                static_cast<float>(static_cast<double>(k) / KittiStyleBag::kPoints));
      ASSERT_NEAR(scan->cloud.time_offsets_s()[k],
                  0.1 * KittiAzimuthFraction(p.x(), p.y(), SpinDirection::kClockwise), 1e-6);
    }
  }
  const DriveStreams& st = r.streams();
  ASSERT_EQ(st.imu.size(), static_cast<size_t>(KittiStyleBag::kOxts));
  for (int m = 0; m < KittiStyleBag::kOxts; ++m) {
    EXPECT_EQ(st.imu[m].stamp.nanoseconds(), t0 + 100000000LL * m);
    EXPECT_EQ(st.imu[m].accel_mps2, Eigen::Vector3d(0.1 * m, -0.2, 9.81));
    EXPECT_EQ(st.imu[m].gyro_radps, Eigen::Vector3d(0.001 * m, 0.002, -0.003 * m));
  }
  // Message 5 has a NaN latitude: skipped and counted; STATUS_FIX = kSingle; unknown covariance.
  ASSERT_EQ(st.gnss.size(), static_cast<size_t>(KittiStyleBag::kOxts - 1));
  EXPECT_EQ(r.NumSkippedGnssFixes(), 1u);
  for (size_t k = 0; k < st.gnss.size(); ++k) {
    const int m = k < 5 ? static_cast<int>(k) : static_cast<int>(k) + 1;
    EXPECT_EQ(st.gnss[k].latitude_deg, 49.0 + 1e-6 * m);
    EXPECT_EQ(st.gnss[k].longitude_deg, 8.4 + 2e-6 * m);
    EXPECT_EQ(st.gnss[k].height_m, 114.0 + 0.1 * m);
    EXPECT_EQ(st.gnss[k].type, GnssFixType::kSingle);
    EXPECT_EQ(st.gnss[k].sigma_horizontal_m, 1.0);
    EXPECT_EQ(st.gnss[k].sigma_vertical_m, 1.5);
    EXPECT_THAT(st.gnss_source[k], HasSubstr("/kitti/oxts/gps/fix message " + std::to_string(m)));
  }
  // Every IMU message has an orientation: the initial state is message 1's, the last at or before
  // the first scan (T0 + 0.1 s): roll 0.01, pitch -0.02, yaw 0.35; its velocity, message 1 (body
  // frame), rotated to ENU.
  const auto rpy = [](int m) {
    return Eigen::Matrix3d(Eigen::AngleAxisd(0.3 + 0.05 * m, Eigen::Vector3d::UnitZ()) *
                           Eigen::AngleAxisd(-0.02 * m, Eigen::Vector3d::UnitY()) *
                           Eigen::AngleAxisd(0.01 * m, Eigen::Vector3d::UnitX()));
  };
  ASSERT_TRUE(st.initial_state.has_value());
  EXPECT_EQ(st.initial_state->stamp.nanoseconds(), t0 + 100000000LL);
  EXPECT_TRUE(st.initial_state->T_world_body.linear().isApprox(rpy(1), 1e-12));
  EXPECT_LE((st.initial_state->v_world_mps - rpy(1) * Eigen::Vector3d(5.1, 0.2, -0.05)).norm(),
            1e-12);
  EXPECT_THAT(st.initial_state_source, HasSubstr("/kitti/oxts/imu message 1;"));
  EXPECT_THAT(st.initial_state_source, HasSubstr("/kitti/oxts/gps/vel message 1 (frame_id "
                                                 "'imu_link')"));

  // A scan range keeps the streams within stream_time_margin_s of it, and the attitude of its
  // first scan.
  RosbagDriveReader::Options o;
  o.first_scan = 2;
  o.last_scan = 3;
  o.stream_time_margin_s = 0.15;
  auto range = RosbagDriveReader::Open(bag, o);
  ASSERT_TRUE(range.ok()) << range.status().ToString();
  const DriveStreams& rs = (*range)->streams();
  ASSERT_EQ((*range)->NumScans(), 2u);
  EXPECT_EQ((*range)->ScanStart(0).nanoseconds(), t0 + 300000000LL);
  ASSERT_EQ(rs.imu.size(), 5u);  // 0.2 .. 0.6 s within [0.15, 0.65]
  EXPECT_EQ(rs.imu.front().stamp.nanoseconds(), t0 + 200000000LL);
  EXPECT_THAT(rs.imu_source.front(), HasSubstr("/kitti/oxts/imu message 2"));
  ASSERT_EQ(rs.gnss.size(), 4u);  // messages 2, 3, 4, 6 (5 is NaN)
  EXPECT_THAT(rs.gnss_source.back(), HasSubstr("/kitti/oxts/gps/fix message 6"));
  ASSERT_TRUE(rs.initial_state.has_value());
  EXPECT_EQ(rs.initial_state->stamp.nanoseconds(), t0 + 300000000LL);
  EXPECT_TRUE(rs.initial_state->T_world_body.linear().isApprox(rpy(3), 1e-12));

  auto topics = RosbagDriveReader::ListTopics(bag);
  ASSERT_TRUE(topics.ok());
  EXPECT_EQ(topics->size(), 5u);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace
}  // namespace slam_mms
