// RunDrive (the loop every app and the Python package run) on a short simulated drive: it gives
// exactly what a host feeding the streams by hand gets, skips and lists unreadable scans, stops
// cleanly on request, and feeds an external POS.
#include "slam_mms/drive/drive_runner.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <set>

#include "slam_mms/drive/open_drive.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "testing/feed_streams.hpp"
#include "testing/simulated_drive.hpp"

namespace slam_mms {
namespace {

// A DriveReader that forwards to another and replaces its streams (to add an external POS).
class StreamsOverride final : public DriveReader {
 public:
  StreamsOverride(const DriveReader& base, DriveStreams streams)
      : base_(base), streams_(std::move(streams)) {}
  std::string Describe() const override { return base_.Describe(); }
  size_t NumScans() const override { return base_.NumScans(); }
  Timestamp ScanStart(size_t i) const override { return base_.ScanStart(i); }
  Timestamp ScanEnd(size_t i) const override { return base_.ScanEnd(i); }
  std::string ScanSource(size_t i) const override { return base_.ScanSource(i); }
  StatusOr<Scan> ReadScan(size_t i) const override { return base_.ReadScan(i); }
  const DriveStreams& streams() const override { return streams_; }
  uint64_t TotalDroppedPoints() const override { return base_.TotalDroppedPoints(); }

 private:
  const DriveReader& base_;
  DriveStreams streams_;
};

void ExpectSameTrajectory(const Trajectory& a, const Trajectory& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.poses()[i].stamp, b.poses()[i].stamp) << i;
    ASSERT_TRUE(a.poses()[i].T_world_body.matrix() == b.poses()[i].T_world_body.matrix())
        << "pose " << i << " differs";
  }
}

class DriveRunnerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto drive = testing::SimulateDrive("slam_mms_drive_runner", /*seed=*/5, kDurationS);
    ASSERT_TRUE(drive.ok()) << drive.status().ToString();
    sim_ = new testing::SimulatedDrive(std::move(drive).value());
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    if (sim_ != nullptr) std::filesystem::remove_all(sim_->dir, ec);
    delete sim_;
    sim_ = nullptr;
  }
  // Where the drive could not be simulated (a full disk) every test fails here, not in a crash.
  void SetUp() override { ASSERT_NE(sim_, nullptr) << "the simulated drive was not written"; }
  static std::unique_ptr<KittiDriveReader> Open(const std::filesystem::path& dir) {
    auto r = KittiDriveReader::Open(dir, KittiRawReader::Options());
    EXPECT_TRUE(r.ok()) << r.status().ToString();
    return r.ok() ? std::move(r).value() : nullptr;
  }
  static MappingSystem::Options OptionsFor(MappingMode mode, const DriveReader& reader) {
    MappingSystem::Options o;
    o.mode = mode;
    o.origin = sim_->origin;
    o.T_body_lidar = reader.streams().T_body_lidar;
    return o;
  }
  static constexpr double kDurationS = 4.0;
  static testing::SimulatedDrive* sim_;
};
testing::SimulatedDrive* DriveRunnerTest::sim_ = nullptr;

TEST_F(DriveRunnerTest, GivesExactlyWhatAHandFedSystemGives) {
  auto reader = Open(sim_->drive_dir);
  ASSERT_NE(reader, nullptr);
  const MappingSystem::Options options = OptionsFor(MappingMode::kFull, *reader);
  const DriveRun run = RunDrive(*reader, options);
  ASSERT_TRUE(run.status.ok()) << run.status.ToString();
  EXPECT_TRUE(run.finished);
  EXPECT_TRUE(run.complete);
  EXPECT_EQ(run.scans_processed, reader->NumScans());
  EXPECT_TRUE(run.skipped_scans.empty());
  ASSERT_TRUE(run.first_scan_start.has_value());
  EXPECT_EQ(*run.first_scan_start, reader->ScanStart(0));

  // By hand: the IMU noise the drive states, the initial state, then IMU/GNSS up to each scan's
  // end, then the scan.
  const DriveStreams& in = reader->streams();
  auto system = MappingSystem::Create(ApplyInputModels(options, in));
  ASSERT_TRUE(system.ok());
  ASSERT_TRUE(in.initial_state.has_value());
  // A KITTI drive's POS record states the OXTS RT3003's attitude accuracy (0.03 / 0.03 / 0.1 deg).
  ASSERT_TRUE(in.initial_attitude_sigma_rpy_rad.has_value());
  EXPECT_TRUE(in.initial_attitude_sigma_rpy_rad->isApprox(
      Eigen::Vector3d(0.03, 0.03, 0.1) * (M_PI / 180.0), 1e-12));
  ASSERT_TRUE((*system)->InitializePos(*in.initial_state, in.initial_attitude_sigma_rpy_rad).ok());
  size_t i_imu = 0, i_gnss = 0;
  for (size_t k = 0; k < reader->NumScans(); ++k) {
    ASSERT_TRUE(testing::FeedStreamsUpTo(system->get(), in.imu, in.gnss, reader->ScanEnd(k), &i_imu,
                                         &i_gnss)
                    .ok());
    auto scan = reader->ReadScan(k);
    ASSERT_TRUE(scan.ok());
    ASSERT_TRUE((*system)->AddScan(*scan).ok());
  }
  ASSERT_TRUE(testing::FeedStreamsUpTo(system->get(), in.imu, in.gnss,
                                       Timestamp::FromNanoseconds(INT64_MAX), &i_imu, &i_gnss)
                  .ok());
  ASSERT_TRUE((*system)->Finish().ok());
  ExpectSameTrajectory(run.trajectory, (*system)->FinalTrajectory());
  EXPECT_EQ(run.map.size(), (*system)->FinalMap().size());
}

// Every map point carries the time and scan of the first point observed in its voxel (LAS GPS time
// and point source ID): inside that scan's [start, end], also when the submap clouds are spilled.
TEST_F(DriveRunnerTest, MapPointsCarryTheTimeAndScanOfTheirFirstObservation) {
  auto reader = Open(sim_->drive_dir);
  ASSERT_NE(reader, nullptr);
  const std::filesystem::path spill = std::filesystem::temp_directory_path() /
                                      ("slam_mms_stamps_spill_" + std::to_string(::getpid()));
  std::filesystem::create_directories(spill);
  for (const MappingMode mode : {MappingMode::kGnssIns, MappingMode::kFull}) {
    MappingSystem::Options options = OptionsFor(mode, *reader);
    options.localizer.submap_duration_s = 1.5;
    const DriveRun run = RunDrive(*reader, options);
    ASSERT_TRUE(run.status.ok()) << run.status.ToString();
    ASSERT_GT(run.map.size(), 1000u);
    ASSERT_EQ(run.map_stamps.size(), run.map.size()) << MappingModeName(mode);
    ASSERT_EQ(run.map_stamps.scan_index.size(), run.map.size());
    std::vector<size_t> per_scan(reader->NumScans(), 0);
    for (size_t i = 0; i < run.map.size(); ++i) {
      const int64_t k = run.map_stamps.scan_index[i];
      ASSERT_GE(k, 0);
      ASSERT_LT(static_cast<size_t>(k), reader->NumScans());
      const int64_t t = run.map_stamps.time_ns[i];
      // The point's own time: its scan's start plus its firing offset (1 us of float rounding).
      EXPECT_GE(t, reader->ScanStart(static_cast<size_t>(k)).nanoseconds() - 1000) << i;
      EXPECT_LE(t, reader->ScanEnd(static_cast<size_t>(k)).nanoseconds() + 1000) << i;
      ++per_scan[static_cast<size_t>(k)];
    }
    // Not all at the scan start: the offsets spread over the scan.
    std::set<int64_t> distinct(run.map_stamps.time_ns.begin(), run.map_stamps.time_ns.end());
    EXPECT_GT(distinct.size(), 100 * reader->NumScans());
    EXPECT_GT(per_scan.front(), 0u);  // the first scan sees most of the map first
    if (mode == MappingMode::kFull) {
      options.localizer.spill_dir = spill;
      const DriveRun spilled = RunDrive(*reader, options);
      ASSERT_TRUE(spilled.status.ok()) << spilled.status.ToString();
      ASSERT_EQ(spilled.map.size(), run.map.size());
      EXPECT_EQ(spilled.map_stamps.time_ns, run.map_stamps.time_ns);
      EXPECT_EQ(spilled.map_stamps.scan_index, run.map_stamps.scan_index);
      EXPECT_EQ(spilled.map.points(), run.map.points());
    }
  }
  std::error_code ec;
  std::filesystem::remove_all(spill, ec);
}

TEST_F(DriveRunnerTest, UnreadableScanIsSkippedListedAndTheRunCompletes) {
  // A copy of the drive with scan 7 truncated (a .bin size not a multiple of 16).
  const std::filesystem::path copy = sim_->dir.string() + "_truncated";
  std::filesystem::remove_all(copy);
  std::filesystem::copy(sim_->dir, copy, std::filesystem::copy_options::recursive);
  const std::filesystem::path drive = copy / sim_->drive_dir.lexically_relative(sim_->dir);
  const std::filesystem::path bin = drive / "velodyne_points" / "data" / "0000000007.bin";
  std::filesystem::resize_file(bin, std::filesystem::file_size(bin) - 3);
  auto reader = Open(drive);
  ASSERT_NE(reader, nullptr);
  const DriveRun run = RunDrive(*reader, OptionsFor(MappingMode::kGnssIns, *reader));
  ASSERT_TRUE(run.status.ok()) << run.status.ToString();
  EXPECT_TRUE(run.complete);
  EXPECT_EQ(run.scans_unreadable, 1u);
  EXPECT_EQ(run.scans_processed, reader->NumScans() - 1);
  ASSERT_EQ(run.skipped_scans.size(), 1u);
  EXPECT_NE(run.skipped_scans[0].find("0000000007.bin"), std::string::npos) << run.skipped_scans[0];
  std::filesystem::remove_all(copy);
}

TEST_F(DriveRunnerTest, StopEndsAfterTheCurrentScanAndKeepsWhatWasComputed) {
  auto reader = Open(sim_->drive_dir);
  ASSERT_NE(reader, nullptr);
  std::atomic<bool> stop{false};
  DriveRunCallbacks callbacks;
  callbacks.stop = &stop;
  size_t last_fed = 0;
  callbacks.on_scan = [&](size_t fed, size_t total) {
    EXPECT_EQ(total, reader->NumScans());
    last_fed = fed;
    if (fed == 10) stop = true;
  };
  const DriveRun run = RunDrive(*reader, OptionsFor(MappingMode::kFull, *reader), callbacks);
  ASSERT_TRUE(run.status.ok()) << run.status.ToString();
  EXPECT_TRUE(run.finished);
  EXPECT_FALSE(run.complete);
  EXPECT_EQ(last_fed, 10u);
  EXPECT_EQ(run.scans_processed, 10u);
  EXPECT_FALSE(run.map.empty());
}

TEST_F(DriveRunnerTest, ExternalPosIsFedThroughWgs84) {
  auto reader = Open(sim_->drive_dir);
  ASSERT_NE(reader, nullptr);
  // The true 100 Hz poses and the scan starts as an external POS in WGS-84 + local ENU attitude.
  std::vector<StampedPose> truth = sim_->poses_100hz.poses();
  truth.insert(truth.end(), sim_->ground_truth.poses().begin(), sim_->ground_truth.poses().end());
  std::stable_sort(truth.begin(), truth.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; });
  const GeographicLib::LocalCartesian lc(sim_->origin.latitude_deg, sim_->origin.longitude_deg,
                                         sim_->origin.height_m);
  DriveStreams streams = reader->streams();
  for (size_t i = 0; i < truth.size(); ++i) {
    if (i > 0 && truth[i].stamp == truth[i - 1].stamp) continue;
    PosRecord r;
    r.stamp = truth[i].stamp;
    const Eigen::Vector3d& p = truth[i].T_world_body.translation();
    lc.Reverse(p.x(), p.y(), p.z(), r.latitude_deg, r.longitude_deg, r.height_m);
    // The local ENU frame at the record is rotated against world (ENU at the origin):
    // R_enu_body = R_world_local^T * R_world_body, with R_world_local what PosRecordsInWorld makes
    // of an identity attitude there.
    auto local = PosRecordsInWorld({r}, sim_->origin);
    ASSERT_TRUE(local.ok());
    r.R_enu_body =
        local->front().T_world_body.linear().transpose() * truth[i].T_world_body.linear();
    streams.pos.push_back(r);
    streams.pos_source.push_back("truth " + std::to_string(i));
  }
  const StreamsOverride with_pos(*reader, streams);
  const DriveRun run = RunDrive(with_pos, OptionsFor(MappingMode::kGnssIns, with_pos));
  ASSERT_TRUE(run.status.ok()) << run.status.ToString();
  ASSERT_EQ(run.trajectory.size(), sim_->ground_truth.size());
  for (size_t i = 0; i < run.trajectory.size(); ++i) {
    const Eigen::Isometry3d& est = run.trajectory.poses()[i].T_world_body;
    const Eigen::Isometry3d& gt = sim_->ground_truth.poses()[i].T_world_body;
    EXPECT_LT((est.translation() - gt.translation()).norm(), 1e-6) << "scan " << i;
    EXPECT_LT(Eigen::AngleAxisd(est.linear().transpose() * gt.linear()).angle(), 1e-8)
        << "scan " << i;
  }
}

// Max position error of `traj` against the ground truth at the scan starts within [a, b) s after
// the first scan.
double MaxErrorIn(const Trajectory& traj, const Trajectory& gt, double a, double b) {
  double worst = 0.0;
  const Timestamp t0 = gt.poses().front().stamp;
  for (const StampedPose& p : traj.poses()) {
    const double t = p.stamp.SecondsSince(t0);
    if (t < a || t >= b) continue;
    auto g = gt.Interpolate(p.stamp, 0.05);
    if (g.ok()) worst = std::max(worst, (p.T_world_body.translation() - g->translation()).norm());
  }
  return worst;
}

TEST_F(DriveRunnerTest, SmoothedPosInAnOutageBeatsTheForwardOneAndFullRunsOnIt) {
  auto reader = Open(sim_->drive_dir);
  ASSERT_NE(reader, nullptr);
  constexpr double kOutageStartS = 1.0, kOutageS = 2.0;
  auto options = [&](MappingMode mode) {
    MappingSystem::Options o = OptionsFor(mode, *reader);
    o.gnss_outages = {{kOutageStartS, kOutageS}};
    return o;
  };
  const DriveRun forward = RunDrive(*reader, options(MappingMode::kGnssIns));
  const DriveRun smoothed = RunDrive(*reader, options(MappingMode::kGnssInsSmoothed));
  DriveRunOptions offline;
  offline.pos = PosWorkflow::kSmoothed;
  const DriveRun full = RunDrive(*reader, options(MappingMode::kFull), {}, offline);
  for (const DriveRun* r : {&forward, &smoothed, &full}) {
    ASSERT_TRUE(r->status.ok()) << r->status.ToString();
    EXPECT_TRUE(r->complete);
    EXPECT_EQ(r->scans_processed, reader->NumScans());
  }
  EXPECT_EQ(smoothed.mode, MappingMode::kGnssInsSmoothed);
  EXPECT_FALSE(forward.smoothed_pos);
  EXPECT_TRUE(smoothed.smoothed_pos);
  EXPECT_TRUE(full.smoothed_pos);
  // The raw fixes reach the system also on the smoothed POS: the outage is seen.
  bool outage_seen = false;
  for (const GnssAvailabilityInterval& a : full.availability) {
    outage_seen = outage_seen || a.availability == GnssAvailability::kOutage;
  }
  EXPECT_TRUE(outage_seen);
  // Level 1 takes F_Odom from the smoothed POS throughout, inside the outage too.
  for (size_t i = 1; i < full.results.size(); ++i) {
    EXPECT_EQ(full.results[i].motion_factor, MotionFactorType::kOdometry) << "scan " << i;
  }
  const double a = kOutageStartS, b = kOutageStartS + kOutageS;
  const double e_fwd = MaxErrorIn(forward.trajectory, sim_->ground_truth, a, b);
  const double e_sm = MaxErrorIn(smoothed.trajectory, sim_->ground_truth, a, b);
  const double e_full = MaxErrorIn(full.trajectory, sim_->ground_truth, a, b);
  std::printf(
      "4 s drive, GNSS outage [%.0f, %.0f) s: max position error gnss_ins %.3f m, "
      "gnss_ins_smoothed %.3f m, full on the smoothed POS %.3f m (smoothing %.2f s)\n",
      a, b, e_fwd, e_sm, e_full, smoothed.smoothing_wall_s);
  EXPECT_LT(e_sm, e_fwd);
  EXPECT_LT(e_full, 0.3);

  // The offline method is RunDrive's, not the streaming system's.
  auto created = MappingSystem::Create(options(MappingMode::kGnssInsSmoothed));
  ASSERT_FALSE(created.ok());
  EXPECT_NE(created.status().message().find("gnss_ins_smoothed"), std::string::npos);
  // Without an initial attitude the smoother cannot start: said so, nothing run.
  DriveStreams streams = reader->streams();
  streams.initial_state.reset();
  const StreamsOverride no_init(*reader, streams);
  const DriveRun failed = RunDrive(no_init, options(MappingMode::kGnssInsSmoothed));
  EXPECT_EQ(failed.status.code(), StatusCode::kFailedPrecondition) << failed.status.ToString();
  EXPECT_EQ(failed.scans_processed, 0u);
}

// The simulated drive states its IMU's datasheet (imu_noise.yaml); RunDrive models the IMU with it
// where use_stated_imu_noise is on, and the result differs from the defaults'.
TEST_F(DriveRunnerTest, StatedImuNoiseIsAppliedUnlessSwitchedOff) {
  auto reader = Open(sim_->drive_dir);
  ASSERT_NE(reader, nullptr);
  const DriveStreams& in = reader->streams();
  ASSERT_TRUE(in.imu_noise.has_value());
  EXPECT_EQ(in.imu_noise_source, (sim_->drive_dir / "imu_noise.yaml").string());
  MappingSystem::Options options = OptionsFor(MappingMode::kGnssIns, *reader);
  EXPECT_TRUE(options.use_stated_imu_noise);  // on by default since session 42 (docs/ins.md)
  const MappingSystem::Options applied = ApplyInputModels(options, in);
  EXPECT_EQ(applied.ins.gyro_noise_density, in.imu_noise->gyro_noise_density);
  EXPECT_EQ(applied.localizer.imu.accel_bias_random_walk, in.imu_noise->AccelBiasRandomWalk());
  EXPECT_NE(applied.ins.gyro_noise_density, options.ins.gyro_noise_density);
  options.use_stated_imu_noise = false;
  EXPECT_EQ(ApplyInputModels(options, in).ins.gyro_noise_density, options.ins.gyro_noise_density);
  const DriveRun off = RunDrive(*reader, options);
  options.use_stated_imu_noise = true;
  const DriveRun on = RunDrive(*reader, options);
  ASSERT_TRUE(off.status.ok() && on.status.ok());
  ASSERT_EQ(off.trajectory.size(), on.trajectory.size());
  EXPECT_FALSE(off.trajectory.poses().back().T_world_body.isApprox(
      on.trajectory.poses().back().T_world_body, 1e-12));
}

// A KITTI raw drive states that its IMU frame is the vehicle's: where vehicle_nhc_sigma_mps is
// set, RunDrive's POS then holds the non-holonomic constraint, unless the caller set
// ins.nhc_sigma_mps itself; an input that does not state it gets none.
TEST_F(DriveRunnerTest, VehicleConstraintWhereTheInputStatesItsImuFrame) {
  auto reader = Open(sim_->drive_dir);
  ASSERT_NE(reader, nullptr);
  DriveStreams in = reader->streams();
  EXPECT_TRUE(in.imu_frame_is_vehicle_frame);
  MappingSystem::Options options = OptionsFor(MappingMode::kGnssIns, *reader);
  EXPECT_EQ(options.ins.nhc_sigma_mps, 0.0);
  EXPECT_EQ(options.vehicle_nhc_sigma_mps, 0.05);  // on by default since session 42 (docs/ins.md)
  EXPECT_TRUE(UsesVehicleConstraint(options, in));
  MappingSystem::Options off = options;
  off.vehicle_nhc_sigma_mps = 0.0;
  EXPECT_FALSE(UsesVehicleConstraint(off, in));
  options.vehicle_nhc_sigma_mps = 0.1;
  EXPECT_TRUE(UsesVehicleConstraint(options, in));
  EXPECT_EQ(ApplyInputModels(options, in).ins.nhc_sigma_mps, options.vehicle_nhc_sigma_mps);
  MappingSystem::Options own = options;
  own.ins.nhc_sigma_mps = 0.3;  // the caller's own value wins
  EXPECT_FALSE(UsesVehicleConstraint(own, in));
  EXPECT_EQ(ApplyInputModels(own, in).ins.nhc_sigma_mps, 0.3);
  MappingSystem::Options never = options;
  never.vehicle_nhc_sigma_mps = 0.0;
  EXPECT_EQ(ApplyInputModels(never, in).ins.nhc_sigma_mps, 0.0);
  DriveStreams unknown = in;
  unknown.imu_frame_is_vehicle_frame = false;
  EXPECT_FALSE(UsesVehicleConstraint(options, unknown));
  EXPECT_EQ(ApplyInputModels(options, unknown).ins.nhc_sigma_mps, 0.0);
  MappingSystem::Options bad = options;
  bad.vehicle_nhc_sigma_mps = -0.1;
  EXPECT_EQ(bad.Validate().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad.Validate().message().find("vehicle_nhc_sigma_mps"), std::string::npos);
  // The constraint changes the POS.
  const DriveRun with = RunDrive(*reader, options);
  const DriveRun without = RunDrive(*reader, never);
  ASSERT_TRUE(with.status.ok() && without.status.ok());
  ASSERT_EQ(with.trajectory.size(), without.trajectory.size());
  EXPECT_FALSE(with.trajectory.poses().back().T_world_body.isApprox(
      without.trajectory.poses().back().T_world_body, 1e-12));
}

TEST(DriveRunOptionsTest, PosWorkflowNames) {
  PosWorkflow p = PosWorkflow::kForward;
  EXPECT_TRUE(ParsePosWorkflow("smoothed", &p));
  EXPECT_EQ(p, PosWorkflow::kSmoothed);
  EXPECT_STREQ(PosWorkflowName(PosWorkflow::kForward), "forward");
  EXPECT_FALSE(ParsePosWorkflow("sbet", &p));
  MappingMode m = MappingMode::kFull;
  EXPECT_TRUE(ParseMappingMode("gnss_ins_smoothed", &m));
  EXPECT_EQ(m, MappingMode::kGnssInsSmoothed);
}

TEST(OpenDriveTest, DetectsTheKindAndNamesWhatIsMissing) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("slam_mms_open_drive_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "folder");
  std::ofstream(dir / "folder" / "scans.csv") << "file,stamp_start_ns,stamp_end_ns\n";
  std::ofstream(dir / "a.bag") << "not a bag";
  EXPECT_EQ(DetectDriveSourceKind(dir / "folder"), DriveSourceKind::kFolder);
  EXPECT_EQ(DetectDriveSourceKind(dir / "a.bag"), DriveSourceKind::kRosbag);
  EXPECT_EQ(DetectDriveSourceKind(dir / "nothing"), DriveSourceKind::kKittiRaw);
  auto missing = OpenDrive(dir / "nothing", DriveSourceOptions());
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("nothing"), std::string::npos);
  DriveSourceOptions with_yaml;
  with_yaml.kind = DriveSourceKind::kKittiRaw;
  with_yaml.extrinsics = dir / "x.yaml";
  // --extrinsics applies to KITTI raw drives too (over calib_imu_to_velo.txt): a missing file is
  // named.
  auto kitti_yaml = OpenDrive(dir / "nothing", with_yaml);
  ASSERT_FALSE(kitti_yaml.ok());
  EXPECT_EQ(kitti_yaml.status().code(), StatusCode::kNotFound);
  EXPECT_NE(kitti_yaml.status().message().find("x.yaml"), std::string::npos);
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
}

}  // namespace
}  // namespace slam_mms
