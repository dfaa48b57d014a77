// DriveSimulator end to end (short drives): layout, determinism, OXTS consistency, outages.
#include "slam_mms/sim/drive_simulator.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <fstream>
#include <sstream>

#include "sim/random.hpp"  // the simulator's seed derivation (MixSeed(seed, 50) for the LiDAR)
#include "slam_mms/core/lie.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/io/kitti_timestamp.hpp"
#include "slam_mms/io/oxts_record.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "testing/test_data.hpp"

namespace slam_mms::sim {
namespace {

namespace fs = std::filesystem;

std::string ReadAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::vector<std::string> Lines(const fs::path& p) {
  std::ifstream f(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(f, l);) out.push_back(l);
  return out;
}

using ScopedDir = testing::ScopedTempDir;

DriveSimulator::Options ShortDrive(uint64_t seed) {
  DriveSimulator::Options o;
  o.seed = seed;
  o.lead_in_s = 4.0;  // already rolling
  o.duration_s = 0.8;
  return o;
}

DriveSimulator::Summary RunTo(const DriveSimulator::Options& o, const fs::path& dir) {
  auto sim = DriveSimulator::Create(o);
  EXPECT_TRUE(sim.ok()) << sim.status().ToString();
  auto summary = sim->Run(dir);
  EXPECT_TRUE(summary.ok()) << summary.status().ToString();
  return *summary;
}

TEST(DriveSimulatorTest, WritesKittiRawLayoutWithGroundTruth) {
  const ScopedDir dir("sim_layout");
  const auto s = RunTo(ShortDrive(1), dir);
  EXPECT_EQ(s.num_scans, 8);
  EXPECT_EQ(s.drive_dir, dir.path / "2026_01_15" / "2026_01_15_drive_0001_sync");
  EXPECT_TRUE(fs::exists(dir.path / "2026_01_15" / "calib_imu_to_velo.txt"));
  const fs::path d = s.drive_dir;
  EXPECT_TRUE(fs::exists(d / "velodyne_points" / "data" / "0000000007.bin"));
  EXPECT_FALSE(fs::exists(d / "velodyne_points" / "data" / "0000000008.bin"));
  EXPECT_EQ(Lines(d / "velodyne_points" / "timestamps_start.txt").size(), 8u);
  EXPECT_EQ(Lines(d / "oxts" / "timestamps.txt").size(), 8u);
  EXPECT_EQ(static_cast<int>(Lines(d / "oxts_100hz" / "timestamps.txt").size()), s.num_imu_records);
  for (const char* f : {"poses_100hz.tum", "scan_start.tum", "scan_trigger.tum", "scan_end.tum",
                        "imu_truth.csv", "gnss.csv", "scene_points.ply", "scenario.json"})
    EXPECT_TRUE(fs::exists(d / "ground_truth" / f)) << f;
  // About 120k points a scan (HDL-64E in a street), 16 bytes each.
  const auto bytes = fs::file_size(d / "velodyne_points" / "data" / "0000000003.bin");
  EXPECT_GT(bytes, 16u * 80000u);
  EXPECT_LT(bytes, 16u * 133400u);
  const std::string json = ReadAll(d / "ground_truth" / "scenario.json");
  EXPECT_NE(json.find("\"seed\": 1"), std::string::npos);
  EXPECT_NE(json.find("\"origin_wgs84\""), std::string::npos);
}

TEST(DriveSimulatorTest, KittiRawReaderReadsTheDriveBackWithConsistentTimes) {
  const ScopedDir dir("sim_reader");
  auto o = ShortDrive(8);
  o.duration_s = 0.5;
  auto sim = DriveSimulator::Create(o);
  ASSERT_TRUE(sim.ok());
  auto s = sim->Run(dir);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  auto reader = KittiRawReader::Open(s->drive_dir);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  ASSERT_EQ(reader->NumScans(), 5u);
  EXPECT_TRUE(reader->HasImu100Hz());
  EXPECT_EQ(reader->OxtsRecords().size(), 5u);
  EXPECT_TRUE(reader->T_lidar_body().isApprox(o.T_lidar_body, 1e-6));
  // The reader's per-point times (from azimuth) match the simulator's firing times.
  const Hdl64Lidar lidar(o.lidar);
  const auto sim_scan = lidar.Simulate(sim->world(), sim->trajectory(), o.T_lidar_body.inverse(),
                                       sim->first_scan_s() + 0.2, 2, MixSeed(o.seed, 50), 2);
  auto scan = reader->ReadScan(2);
  ASSERT_TRUE(scan.ok());
  EXPECT_EQ(scan->stamp_start, sim_scan.scan.stamp_start);
  EXPECT_EQ(scan->cloud.size(), sim_scan.scan.cloud.size());
  double max_dt = 0.0;
  for (size_t i = 0; i < std::min(scan->cloud.size(), sim_scan.scan.cloud.size()); ++i)
    max_dt =
        std::max(max_dt, static_cast<double>(std::abs(scan->cloud.time_offsets_s()[i] -
                                                      sim_scan.scan.cloud.time_offsets_s()[i])));
  EXPECT_LT(max_dt, 2.0 * lidar.PeriodSeconds() / o.lidar.firings_per_revolution);
}

TEST(DriveSimulatorTest, SameSeedGivesIdenticalFilesAndAnotherSeedDoesNot) {
  const ScopedDir a("sim_seed_a"), b("sim_seed_b"), c("sim_seed_c");
  auto o = ShortDrive(42);
  o.duration_s = 0.3;
  const auto sa = RunTo(o, a);
  auto o_threads = o;
  o_threads.num_threads = 1;  // results must not depend on the thread count either
  const auto sb = RunTo(o_threads, b);
  o.seed = 43;
  const auto sc = RunTo(o, c);
  int compared = 0;
  for (const auto& e : fs::recursive_directory_iterator(sa.drive_dir)) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), sa.drive_dir);
    EXPECT_EQ(ReadAll(e.path()), ReadAll(sb.drive_dir / rel)) << rel;
    ++compared;
  }
  EXPECT_GT(compared, 20);
  EXPECT_NE(ReadAll(sa.drive_dir / "velodyne_points/data/0000000001.bin"),
            ReadAll(sc.drive_dir / "velodyne_points/data/0000000001.bin"));
  EXPECT_NE(ReadAll(sa.drive_dir / "oxts/data/0000000001.txt"),
            ReadAll(sc.drive_dir / "oxts/data/0000000001.txt"));
}

TEST(DriveSimulatorTest, OxtsRecordsAreConsistentWithTheGroundTruth) {
  const ScopedDir dir("sim_oxts");
  auto o = ShortDrive(5);
  o.gnss.urban_canyon_scale = 0.0;  // RTK fixed throughout
  auto sim = DriveSimulator::Create(o);
  ASSERT_TRUE(sim.ok());
  auto s = sim->Run(dir);
  ASSERT_TRUE(s.ok());
  const auto& opt = sim->options();
  GeographicLib::LocalCartesian enu(opt.origin_latitude_deg, opt.origin_longitude_deg,
                                    opt.origin_height_m);
  const auto stamps = Lines(s->drive_dir / "oxts" / "timestamps.txt");
  const auto gt = ReadTrajectoryTum(s->drive_dir / "ground_truth" / "poses_100hz.tum");
  ASSERT_TRUE(gt.ok());
  for (size_t i = 0; i < stamps.size(); ++i) {
    auto stamp = ParseKittiTimestamp(stamps[i]);
    ASSERT_TRUE(stamp.ok());
    char name[32];
    std::snprintf(name, sizeof(name), "%010zu.txt", i);
    auto rec = ParseOxtsLine(Lines(s->drive_dir / "oxts" / "data" / name).at(0), name, 1);
    ASSERT_TRUE(rec.ok());
    auto T = gt->Interpolate(*stamp);
    ASSERT_TRUE(T.ok());
    double x, y, z;
    enu.Forward(rec->lat_deg, rec->lon_deg, rec->alt_m, x, y, z);
    EXPECT_LT((Eigen::Vector3d(x, y, z) - T->translation()).norm(), 0.12);
    EXPECT_LT(RotationAngle(OxtsAttitude(*rec).transpose() * T->linear()), 0.01);
    EXPECT_EQ(rec->posmode, 6);
    EXPECT_EQ(rec->navstat, 4);
    EXPECT_NEAR(rec->az, 9.81, 0.5);  // specific force, gravity included
    const double speed = std::hypot(rec->ve, rec->vn);
    EXPECT_NEAR(std::hypot(rec->vf, rec->vl), speed, 1e-9);
    EXPECT_GT(speed, 1.0);  // accelerating from the standstill at the start
  }
  // The scan's trigger lies within half an IMU period of its OXTS record.
  const auto triggers = Lines(s->drive_dir / "velodyne_points" / "timestamps.txt");
  ASSERT_EQ(triggers.size(), stamps.size());
  for (size_t i = 0; i < stamps.size(); ++i)
    EXPECT_LE(
        std::abs(ParseKittiTimestamp(triggers[i])->SecondsSince(*ParseKittiTimestamp(stamps[i]))),
        0.005 + 1e-9);
}

TEST(DriveSimulatorTest, GnssOutageWindowIsRespectedInTheOxtsRecords) {
  const ScopedDir dir("sim_outage");
  auto o = ShortDrive(6);
  o.duration_s = 1.0;
  o.gnss.urban_canyon_scale = 0.0;
  o.gnss.outages = {{0.3, 0.4}};
  auto sim = DriveSimulator::Create(o);
  ASSERT_TRUE(sim.ok());
  auto s = sim->Run(dir);
  ASSERT_TRUE(s.ok());
  const Timestamp first = sim->trajectory().ToTimestamp(sim->first_scan_s());
  const auto stamps = Lines(s->drive_dir / "oxts_100hz" / "timestamps.txt");
  int inside = 0;
  for (size_t i = 0; i < stamps.size(); ++i) {
    const double t = ParseKittiTimestamp(stamps[i])->SecondsSince(first);
    char name[32];
    std::snprintf(name, sizeof(name), "%010zu.txt", i);
    auto rec = ParseOxtsLine(Lines(s->drive_dir / "oxts_100hz" / "data" / name).at(0), name, 1);
    ASSERT_TRUE(rec.ok());
    if (t >= 0.3 + 1e-6 && t < 0.7 - 1e-6) {
      EXPECT_EQ(rec->posmode, 0) << t;
      ++inside;
    } else if (t < 0.3 - 1e-6) {
      EXPECT_EQ(rec->posmode, 6) << t;
    } else if (t > 0.7 + 1e-6) {
      EXPECT_NE(rec->posmode, 6) << "RTK does not re-fix instantly, t=" << t;
    }
  }
  EXPECT_GE(inside, 38);
}

TEST(DriveSimulatorTest, ReadsRealKittiOxtsMotion) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  const fs::path drive = testing::KittiRawDriveDir();  // has oxts/ like an unpacked OXTS drive
  DriveSimulator::Options o;
  o.oxts_drive_dir = drive;
  o.duration_s = 0.3;
  o.lead_in_s = 0.5;
  auto sim = DriveSimulator::Create(o);
  ASSERT_TRUE(sim.ok()) << sim.status().ToString();
  EXPECT_EQ(sim->options().date, "2011_09_26");
  EXPECT_EQ(sim->options().drive_id, 13);
  // The first real record defines the origin: the trajectory starts near (0, 0, 0), as far as
  // the records' positions are held (oxts_truth_position_sigma_m, 1 m, the motion following the
  // records' velocities), and within centimetres when the truth runs through the positions.
  EXPECT_LT(sim->trajectory().Pose(sim->trajectory().start_s()).translation().norm(), 1.0);
  DriveSimulator::Options through = o;
  through.oxts_truth_follows_velocities = false;
  auto through_sim = DriveSimulator::Create(through);
  ASSERT_TRUE(through_sim.ok()) << through_sim.status().ToString();
  EXPECT_LT(
      through_sim->trajectory().Pose(through_sim->trajectory().start_s()).translation().norm(),
      0.2);
  const ScopedDir dir("sim_oxts_real");
  auto s = sim->Run(dir);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->drive_name, "2011_09_26_drive_0013_sync");
  EXPECT_EQ(s->num_scans, 3);
}

// oxts_start_s: the window starts that far into the real motion, the origin stays the drive's
// first record, and the trajectory there is the one fitted over the whole drive.
TEST(DriveSimulatorTest, OxtsStartOffsetsTheWindowIntoTheRealMotion) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  const fs::path drive = testing::KittiRawDriveDir();
  DriveSimulator::Options whole;
  whole.oxts_drive_dir = drive;
  whole.duration_s = 0.3;
  whole.lead_in_s = 0.5;
  auto full = DriveSimulator::Create(whole);
  ASSERT_TRUE(full.ok()) << full.status().ToString();
  DriveSimulator::Options later = whole;
  later.oxts_start_s = 2.0;
  auto cut = DriveSimulator::Create(later);
  ASSERT_TRUE(cut.ok()) << cut.status().ToString();
  EXPECT_DOUBLE_EQ(cut->options().origin_latitude_deg, full->options().origin_latitude_deg);
  EXPECT_NEAR(cut->first_scan_s() - full->first_scan_s(), 2.0, 0.01);
  const double t = cut->first_scan_s() + 0.1;
  const Eigen::Vector3d p_cut = cut->trajectory().Pose(t).translation();
  const Eigen::Vector3d p_full = full->trajectory().Pose(t).translation();
  EXPECT_GT(p_cut.norm(), 5.0) << "drive 0013 moves in its first 2.6 s";
  EXPECT_LT((p_cut - p_full).norm(), 1e-9);
  // A start past the drive's end is an error naming the field.
  DriveSimulator::Options past = whole;
  past.oxts_start_s = 1e4;
  auto none = DriveSimulator::Create(past);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.status().message().find("oxts_start_s"), std::string::npos);
  past.oxts_start_s = -1.0;
  EXPECT_FALSE(DriveSimulator::Create(past).ok());
}

TEST(DriveSimulatorTest, KittiLikeOxtsInertialLagIsWrittenAndFoundByTheReader) {
  // KITTI's OXTS writes its rates, accelerations and velocities about 50 ms behind its positions
  // and attitudes: the simulator can do the same, and the reader finds the lag from the records
  // (and stamps the IMU samples that much early); on time, it finds nothing to correct.
  auto o = ShortDrive(3);
  o.lead_in_s = 8.0;  // the demo route's first turn
  o.duration_s = 2.0;
  o.lidar.firings_per_revolution = 200;  // the scans do not matter here
  for (const double lag : {0.0, 0.05}) {
    const ScopedDir dir("sim_oxts_lag");
    o.oxts_inertial_lag_s = lag;
    const auto s = RunTo(o, dir);
    auto reader = KittiRawReader::Open(s.drive_dir);
    ASSERT_TRUE(reader.ok()) << reader.status().ToString();
    ASSERT_TRUE(reader->oxts_inertial_delay_estimate().has_value());
    const OxtsInertialDelay& e = *reader->oxts_inertial_delay_estimate();
    SCOPED_TRACE("lag " + std::to_string(lag) + ": estimate " + std::to_string(e.delay_s) +
                 " s, RMS " + std::to_string(e.rms_at_delay_radps) + " against " +
                 std::to_string(e.rms_at_zero_radps) + " rad/s");
    if (lag > 0.0) {
      EXPECT_TRUE(e.clear);
      EXPECT_NEAR(e.delay_s, lag, 0.0051);
      EXPECT_EQ(reader->oxts_inertial_delay_s(), e.delay_s);
    } else {
      EXPECT_FALSE(e.clear);
      EXPECT_EQ(reader->oxts_inertial_delay_s(), 0.0);
    }
    // The IMU samples are the records stamped that much early.
    const std::vector<ImuSample> imu = reader->ImuSamples();
    ASSERT_EQ(imu.size(), reader->ImuOxtsRecords().size());
    EXPECT_EQ(imu[10].stamp,
              reader->ImuOxtsRecords()[10].stamp.PlusSeconds(-reader->oxts_inertial_delay_s()));
    // Positions and attitudes stay on time: the records' attitude is the truth's at their stamp.
    const std::string json = ReadAll(s.drive_dir / "ground_truth" / "scenario.json");
    EXPECT_NE(json.find("\"oxts_inertial_lag_s\": " + std::string(lag > 0.0 ? "0.05" : "0.0")),
              std::string::npos);
  }
  // As recorded on request.
  KittiRawReader::Options ro;
  ro.oxts_inertial_delay_s = 0.0;
  const ScopedDir dir("sim_oxts_lag_off");
  const auto s = RunTo(o, dir);
  auto reader = KittiRawReader::Open(s.drive_dir, ro);
  ASSERT_TRUE(reader.ok());
  EXPECT_FALSE(reader->oxts_inertial_delay_estimate().has_value());
  EXPECT_EQ(reader->ImuSamples()[10].stamp, reader->ImuOxtsRecords()[10].stamp);
  ro.oxts_inertial_delay_s = 0.7;
  EXPECT_EQ(KittiRawReader::Open(s.drive_dir, ro).status().code(), StatusCode::kInvalidArgument);
  o.oxts_inertial_lag_s = -0.01;
  EXPECT_FALSE(DriveSimulator::Create(o).ok());
}

}  // namespace
}  // namespace slam_mms::sim
