// DriveSimulator: trajectory + world + sensors -> KITTI raw drive with ground truth.
#include "slam_mms/sim/drive_simulator.hpp"

#include <GeographicLib/LocalCartesian.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "sim/drive_outputs.hpp"
#include "sim/oxts_synthesis.hpp"
#include "sim/random.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/io/imu_noise_yaml.hpp"
#include "slam_mms/io/kitti_raw_writer.hpp"
#include "slam_mms/io/kitti_timestamp.hpp"
#include "slam_mms/io/map_io.hpp"
#include "slam_mms/io/trajectory_io.hpp"

namespace slam_mms::sim {

Eigen::Isometry3d KittiTLidarBody() {
  Eigen::Matrix3d R;
  R << 9.999976e-01, 7.553071e-04, -2.035826e-03, -7.854027e-04, 9.998898e-01, -1.482298e-02,
      2.024406e-03, 1.482454e-02, 9.998881e-01;
  // Re-orthonormalise (the file's 7 digits leave ~1e-7 non-orthogonality).
  const Eigen::Quaterniond q(R);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(-8.086759e-01, 3.195559e-01, -7.997231e-01);
  return T;
}

Eigen::Isometry3d WrittenTLidarBody(const DriveSimulator::Options& o) {
  if (o.calib_error_rpy_deg.isZero(0.0) && o.calib_error_xyz_m.isZero(0.0)) return o.T_lidar_body;
  constexpr double kDegToRad = M_PI / 180.0;
  const Eigen::Vector3d& rpy = o.calib_error_rpy_deg;
  // The error is a rotation about the body axes (on the left) and a lever-arm error in body.
  const Eigen::Matrix3d R_err =
      FromRollPitchYaw(rpy.x() * kDegToRad, rpy.y() * kDegToRad, rpy.z() * kDegToRad);
  const Eigen::Isometry3d T_body_lidar_true = o.T_lidar_body.inverse();
  Eigen::Isometry3d T_body_lidar_written = Eigen::Isometry3d::Identity();
  T_body_lidar_written.linear() = R_err * T_body_lidar_true.linear();
  T_body_lidar_written.translation() = T_body_lidar_true.translation() + o.calib_error_xyz_m;
  return T_body_lidar_written.inverse();
}

Status DriveSimulator::Options::Validate() const {
  auto fail = [](const std::string& name, const std::string& v, const char* rule) {
    return InvalidArgumentError("DriveSimulator::Options::" + name + " = " + v + "; " + rule);
  };
  if (oxts_drive_dir.empty() && scenario != "default" && scenario != "demo" && scenario != "long")
    return fail("scenario", "'" + scenario + "'",
                "must be \"default\", \"demo\" or \"long\" (or set oxts_drive_dir)");
  if (oxts_drive_dir.empty() && scenario == "long" && !(duration_s > 0.0))
    return fail("duration_s", std::to_string(duration_s), "must be > 0 for scenario \"long\"");
  if (route_variant != -1) {
    const int n = oxts_drive_dir.empty() ? NumRouteVariants(scenario) : 0;
    if (n == 0) {
      return fail("route_variant", std::to_string(route_variant),
                  "route variants exist for scenarios \"demo\" and \"default\" only (-1 = none)");
    }
    if (route_variant < 0 || route_variant >= n) {
      const std::string rule = "must be in [0, " + std::to_string(n) + ") for scenario \"" +
                               scenario + "\" (or -1: the scenario's route alone)";
      return fail("route_variant", std::to_string(route_variant), rule.c_str());
    }
  }
  if (!(duration_s >= 0.0)) return fail("duration_s", std::to_string(duration_s), "must be >= 0");
  if (!(lead_in_s >= 0.0)) return fail("lead_in_s", std::to_string(lead_in_s), "must be >= 0");
  if (!(oxts_start_s >= 0.0) || !std::isfinite(oxts_start_s)) {
    return fail("oxts_start_s", std::to_string(oxts_start_s), "must be finite and >= 0");
  }
  if (!(std::abs(origin_latitude_deg) <= 90.0))
    return fail("origin_latitude_deg", std::to_string(origin_latitude_deg), "must be in [-90, 90]");
  if (!(std::abs(origin_longitude_deg) <= 180.0))
    return fail("origin_longitude_deg", std::to_string(origin_longitude_deg),
                "must be in [-180, 180]");
  if (!(gravity_mps2 > 0.0))
    return fail("gravity_mps2", std::to_string(gravity_mps2), "must be > 0");
  if (num_threads < 1) return fail("num_threads", std::to_string(num_threads), "must be >= 1");
  if (!(scene_cloud_voxel_m > 0.0))
    return fail("scene_cloud_voxel_m", std::to_string(scene_cloud_voxel_m), "must be > 0");
  if (!(ins_roll_pitch_sigma_rad >= 0.0 && ins_yaw_sigma_rad >= 0.0 &&
        ins_velocity_sigma_mps >= 0.0))
    return fail("ins_*_sigma", "negative", "must be >= 0");
  if (!(oxts_truth_position_sigma_m > 0.0) || !std::isfinite(oxts_truth_position_sigma_m))
    return fail("oxts_truth_position_sigma_m", std::to_string(oxts_truth_position_sigma_m),
                "must be > 0");
  if (!(oxts_inertial_lag_s >= 0.0 && oxts_inertial_lag_s <= 0.5))
    return fail("oxts_inertial_lag_s", std::to_string(oxts_inertial_lag_s), "must be in [0, 0.5]");
  if (!date.empty() && (date.size() != 10 || date[4] != '_' || date[7] != '_'))
    return fail("date", "'" + date + "'", "must look like 2011_09_26");
  if (!T_lidar_body.matrix().allFinite())
    return fail("T_lidar_body", "non-finite", "must be finite");
  auto vec = [](const Eigen::Vector3d& v) {
    return "(" + std::to_string(v.x()) + ", " + std::to_string(v.y()) + ", " +
           std::to_string(v.z()) + ")";
  };
  if (!calib_error_rpy_deg.allFinite() || !(calib_error_rpy_deg.cwiseAbs().maxCoeff() <= 10.0))
    return fail("calib_error_rpy_deg", vec(calib_error_rpy_deg),
                "each angle must be finite and in [-10, 10] deg");
  if (!imu_mount_error_rpy_deg.allFinite() ||
      !(imu_mount_error_rpy_deg.cwiseAbs().maxCoeff() <= 10.0))
    return fail("imu_mount_error_rpy_deg", vec(imu_mount_error_rpy_deg),
                "each angle must be finite and in [-10, 10] deg");
  if (!calib_error_xyz_m.allFinite() || !(calib_error_xyz_m.cwiseAbs().maxCoeff() <= 1.0))
    return fail("calib_error_xyz_m", vec(calib_error_xyz_m),
                "each component must be finite and in [-1, 1] m");
  if (!(std::abs(lidar_time_offset_s) <= 0.5))
    return fail("lidar_time_offset_s", std::to_string(lidar_time_offset_s),
                "must be finite and in [-0.5, 0.5] s");
  SLAM_MMS_RETURN_IF_ERROR(fit.Validate());
  SLAM_MMS_RETURN_IF_ERROR(world.Validate());
  SLAM_MMS_RETURN_IF_ERROR(lidar.Validate());
  SLAM_MMS_RETURN_IF_ERROR(imu.Validate());
  SLAM_MMS_RETURN_IF_ERROR(gnss.Validate());
  if (std::abs(imu.gravity_mps2 - gravity_mps2) > 1e-12)
    return fail("imu.gravity_mps2", std::to_string(imu.gravity_mps2), "must equal gravity_mps2");
  return OkStatus();
}

struct DriveSimulator::Impl {
  Options options;
  ReferenceTrajectory trajectory;
  std::unique_ptr<CityWorld> world;
  double first_scan_s = 0.0;
  int num_scans = 0;
  double seconds_world = 0.0;
  uint64_t sensor_seed = 1;
  std::vector<ImplausibleMotion> implausible;
};

namespace {

double Seconds(std::chrono::steady_clock::time_point a) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
}

// "2011_09_30_drive_0027_sync" -> date, id.
bool ParseDriveName(const std::string& name, std::string* date, int* id) {
  if (name.size() < 21 || name.compare(10, 7, "_drive_") != 0) return false;
  *date = name.substr(0, 10);
  try {
    *id = std::stoi(name.substr(17, 4));
  } catch (...) {
    return false;
  }
  return true;
}

// The body's samples for an IMU mounted rotated against the car (Options::imu_mount_error_rpy_deg):
// each attitude R_world_car * R_car_body, its yaw kept continuous with the car's; positions and
// velocities (the car's, in world) as they are.
std::vector<PoseSample> MountedBody(const std::vector<PoseSample>& car,
                                    const Eigen::Vector3d& mount_rpy_deg) {
  if (mount_rpy_deg.isZero(0.0)) return car;
  constexpr double kDegToRad = M_PI / 180.0;
  const Eigen::Matrix3d R_car_body = FromRollPitchYaw(
      mount_rpy_deg.x() * kDegToRad, mount_rpy_deg.y() * kDegToRad, mount_rpy_deg.z() * kDegToRad);
  std::vector<PoseSample> body = car;
  for (PoseSample& s : body) {
    const Eigen::Matrix3d R_world_body =
        FromRollPitchYaw(s.rpy_rad.x(), s.rpy_rad.y(), s.rpy_rad.z()) * R_car_body;
    Eigen::Vector3d rpy = RollPitchYaw(R_world_body);
    rpy.z() = s.rpy_rad.z() + std::remainder(rpy.z() - s.rpy_rad.z(), 2.0 * M_PI);
    s.rpy_rad = rpy;
  }
  return body;
}

}  // namespace

DriveSimulator::DriveSimulator(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DriveSimulator::DriveSimulator(DriveSimulator&&) noexcept = default;
DriveSimulator& DriveSimulator::operator=(DriveSimulator&&) noexcept = default;
DriveSimulator::~DriveSimulator() = default;

StatusOr<DriveSimulator> DriveSimulator::Create(const Options& options_in) {
  SLAM_MMS_RETURN_IF_ERROR(options_in.Validate());
  auto impl = std::make_unique<Impl>();
  Options& o = impl->options;
  o = options_in;
  o.world.seed = MixSeed(o.seed, 10);
  Timestamp epoch;
  std::vector<PoseSample> samples;
  double span_begin_s = -std::numeric_limits<double>::infinity();  // oxts_start_s, if any
  std::optional<std::pair<double, double>> window;  // of the fitted motion, with oxts_start_s
  if (!o.oxts_drive_dir.empty()) {
    SLAM_MMS_ASSIGN_OR_RETURN(
        OxtsPoseSamples loaded,
        LoadOxtsPoseSamples(o.oxts_drive_dir, o.origin_latitude_deg, o.origin_longitude_deg,
                            o.origin_height_m, o.origin_from_oxts));
    epoch = loaded.epoch;
    samples = std::move(loaded.samples);
    for (PoseSample& sample : samples) {
      if (o.oxts_truth_follows_velocities) {
        sample.position_sigma_m = std::max(sample.position_sigma_m, o.oxts_truth_position_sigma_m);
      } else {
        sample.has_velocity = false;
        sample.position_sigma_m = 0.0;
      }
    }
    if (o.oxts_start_s > 0.0) {
      // The span simulated: from oxts_start_s, to 5 s past the last scan (spline margin), of the
      // motion fitted over the whole drive (a window is the same motion as the whole drive).
      const double begin = samples.empty() ? 0.0 : samples.front().t_s + o.oxts_start_s;
      const double end = o.duration_s > 0.0 ? begin + o.lead_in_s + o.duration_s + 5.0
                                            : std::numeric_limits<double>::infinity();
      // From the last record at or before `begin`.
      int kept = 0;
      double kept_from = 0.0, kept_to = 0.0;
      for (size_t i = 0; i < samples.size(); ++i) {
        const bool next_after = i + 1 < samples.size() && samples[i + 1].t_s > begin + 1e-9;
        if ((samples[i].t_s >= begin - 1e-9 || next_after) && samples[i].t_s <= end) {
          if (kept++ == 0) kept_from = samples[i].t_s;
          kept_to = samples[i].t_s;
        }
      }
      span_begin_s = begin;
      if (kept < 4) {
        return InvalidArgumentError(
            "DriveSimulator: oxts_start_s = " + std::to_string(o.oxts_start_s) + " leaves " +
            std::to_string(kept) + " OXTS records of " + o.oxts_drive_dir.string() +
            " (need >= 4; the drive spans " +
            std::to_string(samples.back().t_s - samples.front().t_s) + " s)");
      }
      window = {kept_from, kept_to};
    }
    o.origin_latitude_deg = loaded.origin_latitude_deg;
    o.origin_longitude_deg = loaded.origin_longitude_deg;
    o.origin_height_m = loaded.origin_height_m;
    std::string name = o.oxts_drive_dir.filename().string();
    if (name.empty()) name = o.oxts_drive_dir.parent_path().filename().string();
    std::string date;
    int id = 0;
    const bool parsed = ParseDriveName(name, &date, &id);
    if (o.date.empty()) o.date = parsed ? date : "2011_01_01";
    if (o.drive_id < 0) o.drive_id = parsed ? id : 1;
    if (loaded.num_dropped > 0) {
      SLAM_MMS_LOG(kInfo) << "sim: dropped " << loaded.num_dropped << " OXTS records of " << name;
    }
  } else {
    SLAM_MMS_ASSIGN_OR_RETURN(epoch, ParseKittiTimestamp(o.start_time));
    if (o.route_variant >= 0) {
      SLAM_MMS_ASSIGN_OR_RETURN(samples, RouteVariantSamples(o.scenario, o.route_variant));
      epoch = epoch.PlusSeconds(3600.0 * o.route_variant);
    } else {
      samples = o.scenario == "long"   ? LongUrbanRouteSamples(o.duration_s + o.lead_in_s + 5.0)
                : o.scenario == "demo" ? DemoUrbanRouteSamples()
                                       : DefaultUrbanRouteSamples();
    }
    if (o.date.empty()) o.date = "2026_01_15";
    if (o.drive_id < 0) o.drive_id = o.route_variant >= 0 ? o.route_variant + 1 : 1;
  }
  // Variant 0 keeps the seed's noise (the drive without variants differs only in its world).
  impl->sensor_seed =
      o.route_variant > 0 ? MixSeed(o.seed, 1000 + static_cast<uint64_t>(o.route_variant)) : o.seed;
  SLAM_MMS_ASSIGN_OR_RETURN(
      impl->trajectory,
      ReferenceTrajectory::Fit(epoch, MountedBody(samples, o.imu_mount_error_rpy_deg), o.fit));
  if (window) {
    SLAM_MMS_ASSIGN_OR_RETURN(impl->trajectory,
                              impl->trajectory.Restricted(window->first, window->second));
  }
  if (!o.oxts_drive_dir.empty()) {
    for (const ImplausibleMotion& span : FindImplausibleMotion(samples)) {
      if (span.to_s < impl->trajectory.start_s() || span.from_s > impl->trajectory.end_s()) {
        continue;
      }
      SLAM_MMS_LOG(kWarning) << "sim: OXTS records " << span.first_record << ".."
                             << span.last_record << " (" << span.from_s << "-" << span.to_s
                             << " s) of " << o.oxts_drive_dir.string()
                             << " are not a road car's motion (sideways up to "
                             << span.max_sideways_mps << " m/s, vertical up to "
                             << span.max_vertical_mps << " m/s); the simulated car follows them";
      impl->implausible.push_back(span);
    }
  }
  const ReferenceTrajectory& traj = impl->trajectory;
  // Timeline: the first scan after the lead-in, then scans back to back.
  Hdl64Lidar lidar(o.lidar);
  const double period = lidar.PeriodSeconds();
  impl->first_scan_s = std::max(traj.start_s(), span_begin_s) + o.lead_in_s;
  const double usable = traj.end_s() - 0.05 - impl->first_scan_s - lidar.LastFiringOffsetSeconds();
  if (usable < 0.0) {
    return InvalidArgumentError("DriveSimulator: the trajectory (" +
                                std::to_string(traj.DurationSeconds()) +
                                " s) is too short for the lead-in and one scan");
  }
  int n = static_cast<int>(std::floor(usable / period + 1e-9)) + 1;
  if (o.duration_s > 0.0)
    n = std::min(n, std::max(1, static_cast<int>(std::floor(o.duration_s / period + 1e-9))));
  impl->num_scans = n;
  const double last_end = impl->first_scan_s + (n - 1) * period + lidar.LastFiringOffsetSeconds();
  const auto t0 = std::chrono::steady_clock::now();
  if (o.route_variant >= 0) {
    // One city for all variants: along every variant's whole route, in variant order, whichever
    // variant (and duration) is simulated.
    std::vector<ReferenceTrajectory> routes;
    for (int k = 0; k < NumRouteVariants(o.scenario); ++k) {
      if (k == o.route_variant) {
        routes.push_back(traj);
        continue;
      }
      SLAM_MMS_ASSIGN_OR_RETURN(std::vector<PoseSample> route, RouteVariantSamples(o.scenario, k));
      SLAM_MMS_ASSIGN_OR_RETURN(ReferenceTrajectory fitted,
                                ReferenceTrajectory::Fit(epoch, route, o.fit));
      routes.push_back(std::move(fitted));
    }
    std::vector<CityWorld::PathSpan> spans;
    for (const ReferenceTrajectory& r : routes) spans.push_back({&r, r.start_s(), r.end_s()});
    SLAM_MMS_ASSIGN_OR_RETURN(CityWorld world, CityWorld::Build(spans, o.world));
    impl->world = std::make_unique<CityWorld>(std::move(world));
  } else {
    SLAM_MMS_ASSIGN_OR_RETURN(
        CityWorld world,
        CityWorld::Build(traj, o.world, traj.start_s(), std::min(traj.end_s(), last_end + 1.0)));
    impl->world = std::make_unique<CityWorld>(std::move(world));
  }
  impl->seconds_world = Seconds(t0);
  return DriveSimulator(std::move(impl));
}

const ReferenceTrajectory& DriveSimulator::trajectory() const { return impl_->trajectory; }
const CityWorld& DriveSimulator::world() const { return *impl_->world; }
const DriveSimulator::Options& DriveSimulator::options() const { return impl_->options; }
double DriveSimulator::first_scan_s() const { return impl_->first_scan_s; }
int DriveSimulator::num_scans() const { return impl_->num_scans; }
double DriveSimulator::seconds_world_build() const { return impl_->seconds_world; }
uint64_t DriveSimulator::sensor_seed() const { return impl_->sensor_seed; }
const std::vector<ImplausibleMotion>& DriveSimulator::implausible_motion() const {
  return impl_->implausible;
}

StatusOr<DriveSimulator::Summary> DriveSimulator::Run(const std::filesystem::path& out_dir,
                                                      const Progress& progress,
                                                      const std::atomic<bool>* stop) {
  const auto t_run = std::chrono::steady_clock::now();
  const Options& o = impl_->options;
  const ReferenceTrajectory& traj = impl_->trajectory;
  const CityWorld& world = *impl_->world;
  Summary summary;
  char drive_name[64];
  std::snprintf(drive_name, sizeof(drive_name), "%s_drive_%04d_sync", o.date.c_str(), o.drive_id);
  summary.drive_name = drive_name;
  summary.date_dir = out_dir / o.date;
  summary.drive_dir = summary.date_dir / drive_name;
  KittiRawWriter::Options wopt;
  wopt.overwrite = o.overwrite;
  SLAM_MMS_ASSIGN_OR_RETURN(KittiRawWriter writer, KittiRawWriter::Create(summary.drive_dir, wopt));
  // The true calibration, or a wrong one on purpose (Options::calib_error_*).
  SLAM_MMS_RETURN_IF_ERROR(writer.WriteCalibration(WrittenTLidarBody(o)));
  // The IMU's datasheet, as a user states theirs (io/imu_noise_yaml.hpp); not ground truth.
  if (const std::optional<ImuNoiseSpec> spec = o.imu.NoiseSpec()) {
    SLAM_MMS_RETURN_IF_ERROR(WriteImuNoiseYaml(*spec, summary.drive_dir / kImuNoiseFileName));
  }
  const std::filesystem::path gt_dir = summary.drive_dir / "ground_truth";
  std::error_code ec;
  std::filesystem::create_directories(gt_dir, ec);
  if (ec) return InternalError("cannot create " + gt_dir.string() + ": " + ec.message());

  Hdl64Lidar lidar(o.lidar);
  const double period = lidar.PeriodSeconds();
  int n_scans = impl_->num_scans;
  const double first = impl_->first_scan_s;
  double last_end = first + (n_scans - 1) * period + lidar.LastFiringOffsetSeconds();
  const Eigen::Isometry3d T_body_lidar = o.T_lidar_body.inverse();

  // ---- 100 Hz IMU / GNSS / POS records ---------------------------------------------------------
  GeographicLib::LocalCartesian enu(o.origin_latitude_deg, o.origin_longitude_deg,
                                    o.origin_height_m);
  const uint64_t sensor_seed = impl_->sensor_seed;
  ImuSimulator imu(o.imu, MixSeed(sensor_seed, 20));
  GnssSimulator gnss(o.gnss, MixSeed(sensor_seed, 30));
  InsErrorProcess ins(o.ins_roll_pitch_sigma_rad, o.ins_yaw_sigma_rad, o.ins_velocity_sigma_mps,
                      MixSeed(sensor_seed, 40));
  const double imu_dt = 1.0 / o.imu.rate_hz;
  std::vector<double> rec_t;
  std::vector<OxtsRecord> records;
  GroundTruthLog log;
  double blockage = 0.0, next_blockage_t = -1e9;
  int counts[4] = {0, 0, 0, 0};
  for (int i = 0;; ++i) {
    const double t = traj.start_s() + i * imu_dt;
    if (t > std::min(traj.end_s(), last_end + 0.5) + 1e-9) break;
    const BodyState state = traj.Evaluate(t);
    const Timestamp stamp = traj.ToTimestamp(t);
    // The records' inertial outputs from the motion oxts_inertial_lag_s earlier (KITTI-like).
    const bool lagged = o.oxts_inertial_lag_s > 0.0;
    const BodyState inertial_state =
        lagged ? traj.Evaluate(std::max(traj.start_s(), t - o.oxts_inertial_lag_s)) : state;
    const ImuSample meas = imu.Measure(inertial_state, stamp);
    if (t >= next_blockage_t) {  // sky view of the antenna (0.75 m above the IMU), 2 Hz
      blockage = world.SkyBlockage(state.T_world_body * Eigen::Vector3d(0.0, 0.0, 0.75));
      next_blockage_t = t + 0.5;
    }
    const GnssSample g = gnss.Step(t - first, blockage);
    ins.Step(imu_dt, g.state != GnssState::kNone);
    records.push_back(SynthesizeOxts(state, inertial_state, meas, g, ins, enu));
    rec_t.push_back(t);
    if (t >= first && t <= last_end) ++counts[static_cast<int>(g.state)];
    SLAM_MMS_RETURN_IF_ERROR(writer.AddImuOxts(stamp, records.back()));
    log.Add(stamp, state, ImuSimulator::TrueMeasurement(state, stamp, o.gravity_mps2), imu, g);
  }
  summary.num_imu_records = static_cast<int>(records.size());
  const int total_in_span = counts[0] + counts[1] + counts[2] + counts[3];
  if (total_in_span > 0) {
    summary.fraction_none = static_cast<double>(counts[0]) / total_in_span;
    summary.fraction_sps = static_cast<double>(counts[1]) / total_in_span;
    summary.fraction_float = static_cast<double>(counts[2]) / total_in_span;
    summary.fraction_fixed = static_cast<double>(counts[3]) / total_in_span;
  }

  // ---- scans --------------------------------------------------------------------------------
  SceneCloudAccumulator scene(o.scene_cloud_voxel_m);
  Trajectory gt_start, gt_trigger, gt_end;
  for (int k = 0; k < n_scans; ++k) {
    if (stop != nullptr && stop->load() && k > 0) {
      summary.stopped = true;
      n_scans = k;
      last_end = first + (n_scans - 1) * period + lidar.LastFiringOffsetSeconds();
      break;
    }
    const double ts = first + k * period;
    auto t_l = std::chrono::steady_clock::now();
    Hdl64Lidar::Output out =
        lidar.Simulate(world, traj, T_body_lidar, ts, k, MixSeed(sensor_seed, 50), o.num_threads);
    summary.seconds_lidar += Seconds(t_l);
    auto t_w = std::chrono::steady_clock::now();
    if (o.write_scene_cloud) scene.Add(out.p_world_exact, out.scan.cloud.intensities());
    summary.num_points += out.scan.cloud.size();
    // The ground truth is on the true (IMU) clock; the LiDAR's stamps lag by lidar_time_offset_s.
    const Timestamp true_start = out.scan.stamp_start;
    const Timestamp true_trigger = out.scan.stamp_trigger;
    const Timestamp true_end = out.scan.stamp_end;
    if (o.lidar_time_offset_s != 0.0) {
      out.scan.stamp_start = true_start.PlusSeconds(-o.lidar_time_offset_s);
      out.scan.stamp_trigger = true_trigger.PlusSeconds(-o.lidar_time_offset_s);
      out.scan.stamp_end = true_end.PlusSeconds(-o.lidar_time_offset_s);
    }
    SLAM_MMS_RETURN_IF_ERROR(writer.AddScan(out.scan));
    // The 10 Hz sync record: the 100 Hz record nearest the trigger.
    const double tt = ts + 0.5 * period;
    const size_t j = static_cast<size_t>(std::clamp<long>(
        std::lround((tt - traj.start_s()) / imu_dt), 0L, static_cast<long>(records.size()) - 1));
    SLAM_MMS_RETURN_IF_ERROR(writer.AddOxts(traj.ToTimestamp(rec_t[j]), records[j]));
    SLAM_MMS_RETURN_IF_ERROR(gt_start.Add(true_start, traj.Pose(ts)));
    SLAM_MMS_RETURN_IF_ERROR(gt_trigger.Add(true_trigger, traj.Pose(tt)));
    SLAM_MMS_RETURN_IF_ERROR(gt_end.Add(true_end, traj.Pose(ts + lidar.LastFiringOffsetSeconds())));
    summary.seconds_writing += Seconds(t_w);
    if (progress) progress(k + 1, n_scans);
  }
  auto t_w = std::chrono::steady_clock::now();
  SLAM_MMS_RETURN_IF_ERROR(writer.Finish());
  summary.num_scans = n_scans;
  summary.simulated_seconds = last_end - first;
  for (double t = first + 0.1; t <= last_end + 1e-9; t += 0.1)
    summary.path_length_m += (traj.Pose(t).translation() - traj.Pose(t - 0.1).translation()).norm();

  // ---- ground truth -------------------------------------------------------------------------
  SLAM_MMS_RETURN_IF_ERROR(WriteTrajectoryTum(log.poses, gt_dir / "poses_100hz.tum"));
  SLAM_MMS_RETURN_IF_ERROR(WriteTrajectoryTum(gt_start, gt_dir / "scan_start.tum"));
  SLAM_MMS_RETURN_IF_ERROR(WriteTrajectoryTum(gt_trigger, gt_dir / "scan_trigger.tum"));
  SLAM_MMS_RETURN_IF_ERROR(WriteTrajectoryTum(gt_end, gt_dir / "scan_end.tum"));
  SLAM_MMS_RETURN_IF_ERROR(log.WriteCsv(gt_dir));
  if (o.write_scene_cloud) {
    MapCloud map = scene.Take();
    summary.num_scene_points = map.cloud.size();
    SLAM_MMS_RETURN_IF_ERROR(WritePly(map, gt_dir / "scene_points.ply"));
  }
  summary.seconds_writing += Seconds(t_w);
  summary.seconds_total = Seconds(t_run);
  SLAM_MMS_RETURN_IF_ERROR(WriteScenarioJson(o, *this, summary, gt_dir / "scenario.json"));
  return summary;
}

}  // namespace slam_mms::sim
