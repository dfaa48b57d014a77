// slam_mms_sim: writes a simulated drive in KITTI raw layout with true ground truth.
//
//   slam_mms_sim --scenario default --seed N --duration S --out DIR
//   slam_mms_sim --oxts OXTS_DRIVE_DIR --seed N --duration S --out DIR     (real KITTI motion)
//
//   slam_mms_sim --scenario demo --seed N --route-variant K --out DIR   (drive K + 1 of one city)
//
// Further options:
//   --route-variant K                  route variant K of scenario demo or default (0, 1, 2): every
//                                      variant of one seed drives through the same city, in one
//                                      world frame; variant K starts K hours later, has its own
//                                      sensor noise and is written as drive K + 1 (unless
//                                      --drive-id); see docs/simulator.md "Route variants"
//   --gnss-outage START_S:DURATION_S   (repeatable; relative to the first scan)
//   --imu-grade perfect|consumer|tactical|navigation   (default tactical, RT3003-like)
//   --gnss-quality fixed|float|sps     best GNSS solution reachable (default fixed)
//   --urban-canyon SCALE               sky-blockage degradation scale (default 1, 0 = off)
//   --origin LAT,LON,H                 WGS-84 origin of the world frame (default Karlsruhe; with
//                                      --oxts the first record unless --origin is given)
//   --elevation-bias DEG               KITTI-like 0.205 deg low points (default 0)
//   --oxts-inertial-lag S              KITTI-like: OXTS rates, accelerations, velocities S late
//                                      (default 0; KITTI about 0.05)
//   --lead-in S                        IMU/POS records before the first scan (default 1)
//   --oxts-start S                     with --oxts: start the lead-in S seconds into the drive
//   --oxts-truth-through-positions     with --oxts: the true motion is a spline through the
//                                      records' positions (before session 26), not their
//                                      velocities held to the positions within 1 m
//   --calib-error-rpy-deg R,P,Y        write calib_imu_to_velo.txt wrong on purpose: rotated by
//                                      Rz(Y) Ry(P) Rx(R) about the body axes (each |.| <= 10 deg)
//   --calib-error-xyz-m X,Y,Z          ... and its lever arm off by X,Y,Z [m] in the body frame
//                                      (each |.| <= 1 m)
//   --imu-mount-error-rpy-deg R,P,Y    the IMU (body) mounted rotated against the car by
//                                      Rz(Y) Ry(P) Rx(R) (each |.| <= 10 deg): the car's motion
//                                      kept, the body's attitude (truth, IMU, INS records) rotated
//   --lidar-time-offset-s T            LiDAR clock T s behind the IMU's: the scan stamps written
//                                      are true - T (|T| <= 0.5; the ground truth stays true)
// Realism models (all off by default; docs/simulator.md "Realism models"):
//   --laser-intrinsics                 per-laser calibration residuals of an HDL-64E (0.03 deg
//                                      elevation and azimuth, 2 cm range offset, 1e-3 scale)
//   --beam-divergence-mrad D           beam divergence (HDL-64E about 2): mixed pixels at edges
//   --ground-roughness                 road 5 mm, sidewalk/curb 8 mm, terrain 3 cm RMS texture
//   --volumetric-vegetation            tree crowns and hedges as scattering volumes
//   --realism                          all four of the above (divergence 2 mrad)
//   --max-range M                      LiDAR range limit [m] (default 120; KITTI's scans end near
//   80)
//   --threads N (default 2)  --no-scene-cloud  --scene-voxel M  --drive-id N  --date YYYY_MM_DD
// --oxts also accepts a KITTI OXTS archive <drive>_sync.tar.gz (unpacked with `tar` to a temp dir).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "app_common/huge_page_malloc.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms/version.hpp"

namespace fs = std::filesystem;
using slam_mms::sim::DriveSimulator;

namespace {

// Prints the usage (to stderr after an error, else to stdout); returns 2 (a bad command line).
int Usage(const std::string& error) {
  if (!error.empty()) std::cerr << "slam_mms_sim: " << error << "\n";
  (error.empty() ? std::cout : std::cerr)
      << "usage: slam_mms_sim (--scenario default | --oxts OXTS_DRIVE_DIR) --seed N --duration S "
         "--out DIR\n"
         "       [--route-variant K]   (scenarios demo and default: K in 0..2, drives of one "
         "city)\n"
         "       [--gnss-outage START_S:DURATION_S]... [--imu-grade "
         "perfect|consumer|tactical|navigation]\n"
         "       [--gnss-quality fixed|float|sps] [--urban-canyon SCALE] [--origin LAT,LON,H]\n"
         "       [--elevation-bias DEG] [--oxts-inertial-lag S] [--lead-in S] [--oxts-start S] "
         "[--oxts-truth-through-positions] [--threads N] "
         "[--no-scene-cloud] "
         "[--scene-voxel M]\n"
         "       [--drive-id N] [--date YYYY_MM_DD]\n"
         "       [--laser-intrinsics] [--beam-divergence-mrad D] [--ground-roughness]\n"
         "       [--volumetric-vegetation] [--realism]   (realism models, off by default)\n"
         "       [--max-range M]   (LiDAR range limit, default 120 m)\n"
         "       [--calib-error-rpy-deg R,P,Y] [--calib-error-xyz-m X,Y,Z] "
         "[--lidar-time-offset-s T] [--imu-mount-error-rpy-deg R,P,Y]\n"
         "         (a wrong calib_imu_to_velo.txt and a LiDAR clock T s behind the IMU's, on "
         "purpose;\n"
         "          scenario.json keeps the truth; see docs/simulator.md)\n"
         "       slam_mms_sim --version | --help\n"
         "Values go after the flag or after '=' (--out=DIR).\n";
  return 2;
}

// Unpacks a <drive>_sync.tar.gz into a fresh temp dir; returns the drive folder.
bool Unpack(const fs::path& archive, fs::path* drive_dir) {
  const fs::path tmp =
      fs::temp_directory_path() /
      ("slam_mms_sim_oxts_" +
       std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
  fs::create_directories(tmp);
  const std::string cmd = "tar -xzf '" + archive.string() + "' -C '" + tmp.string() + "'";
  if (std::system(cmd.c_str()) != 0) return false;
  for (const auto& e : fs::directory_iterator(tmp)) {
    if (e.is_directory()) {
      *drive_dir = e.path();
      return true;
    }
  }
  return false;
}

// "A:B" or "A,B,C" into numbers; false where a part is not a finite number.
bool SplitNumbers(const std::string& text, char sep, std::vector<double>* out) {
  out->clear();
  size_t begin = 0;
  while (true) {
    const size_t end = text.find(sep, begin);
    const std::string part = text.substr(begin, end == std::string::npos ? end : end - begin);
    char* stop = nullptr;
    const double v = std::strtod(part.c_str(), &stop);
    if (part.empty() || *stop != '\0' || !std::isfinite(v)) return false;
    out->push_back(v);
    if (end == std::string::npos) return true;
    begin = end + 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  slam_mms::app::ReexecWithHugePageMalloc(argv);
  slam_mms::SetLogSink(slam_mms::StderrLogSink());
  DriveSimulator::Options o;
  fs::path out;
  std::string imu_grade = "tactical";
  std::string gnss_quality, origin;
  std::vector<std::string> outages;
  bool help = false, version = false, no_scene_cloud = false;
  bool oxts_truth_through_positions = false;
  bool laser_intrinsics = false, ground_roughness = false, realism = false;
  double beam_divergence_mrad = 0.0;
  std::vector<double> calib_error_rpy_deg, calib_error_xyz_m;
  // CLI11: `--flag value` and `--flag=value`; numbers are checked by CLI11 (a bad one: exit 2).
  CLI::App app("slam_mms_sim", "slam_mms_sim");
  app.set_help_flag();
  app.add_flag("-h,--help", help);
  app.add_flag("--version", version);
  app.add_option("--scenario", o.scenario);
  app.add_option("--route-variant", o.route_variant);
  app.add_option("--oxts", o.oxts_drive_dir);
  app.add_option("--oxts-start", o.oxts_start_s);
  app.add_flag("--oxts-truth-through-positions", oxts_truth_through_positions);
  app.add_option("--seed", o.seed);
  app.add_option("--duration", o.duration_s);
  app.add_option("--out", out);
  app.add_option("--gnss-outage", outages)->expected(1, CLI::detail::expected_max_vector_size);
  app.add_option("--imu-grade", imu_grade);
  app.add_option("--gnss-quality", gnss_quality)->check(CLI::IsMember({"fixed", "float", "sps"}));
  app.add_option("--urban-canyon", o.gnss.urban_canyon_scale);
  app.add_option("--origin", origin);
  app.add_option("--elevation-bias", o.lidar.elevation_bias_deg);
  app.add_option("--oxts-inertial-lag", o.oxts_inertial_lag_s);
  app.add_option("--lead-in", o.lead_in_s);
  app.add_option("--threads", o.num_threads);
  app.add_flag("--no-scene-cloud", no_scene_cloud);
  app.add_option("--scene-voxel", o.scene_cloud_voxel_m);
  app.add_option("--drive-id", o.drive_id);
  app.add_option("--date", o.date);
  app.add_option("--calib-error-rpy-deg", calib_error_rpy_deg)->delimiter(',')->expected(3);
  app.add_option("--calib-error-xyz-m", calib_error_xyz_m)->delimiter(',')->expected(3);
  std::vector<double> imu_mount_error_rpy_deg;
  app.add_option("--imu-mount-error-rpy-deg", imu_mount_error_rpy_deg)->delimiter(',')->expected(3);
  app.add_option("--lidar-time-offset-s", o.lidar_time_offset_s);
  app.add_flag("--laser-intrinsics", laser_intrinsics);
  app.add_option("--beam-divergence-mrad", beam_divergence_mrad);
  app.add_flag("--ground-roughness", ground_roughness);
  app.add_flag("--volumetric-vegetation", o.world.volumetric_vegetation);
  app.add_flag("--realism", realism);
  app.add_option("--max-range", o.lidar.max_range_m);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return Usage(e.what());
  }
  if (help) {
    Usage("");
    return 0;
  }
  if (version) {
    std::printf("slam_mms_sim %s\n", SLAM_MMS_VERSION_STRING);
    return 0;
  }
  if (no_scene_cloud) o.write_scene_cloud = false;
  if (oxts_truth_through_positions) o.oxts_truth_follows_velocities = false;
  if (realism) {
    laser_intrinsics = ground_roughness = o.world.volumetric_vegetation = true;
    if (app.count("--beam-divergence-mrad") == 0) beam_divergence_mrad = 2.0;
  }
  if (laser_intrinsics) o.lidar.EnableLaserIntrinsicErrors();
  if (ground_roughness) o.world.EnableGroundRoughness();
  o.lidar.beam_divergence_rad = beam_divergence_mrad * 1e-3;
  if (!calib_error_rpy_deg.empty()) {
    o.calib_error_rpy_deg =
        Eigen::Vector3d(calib_error_rpy_deg[0], calib_error_rpy_deg[1], calib_error_rpy_deg[2]);
  }
  if (!calib_error_xyz_m.empty()) {
    o.calib_error_xyz_m =
        Eigen::Vector3d(calib_error_xyz_m[0], calib_error_xyz_m[1], calib_error_xyz_m[2]);
  }
  if (!imu_mount_error_rpy_deg.empty()) {
    o.imu_mount_error_rpy_deg = Eigen::Vector3d(
        imu_mount_error_rpy_deg[0], imu_mount_error_rpy_deg[1], imu_mount_error_rpy_deg[2]);
  }
  std::vector<double> numbers;
  for (const std::string& v : outages) {
    if (!SplitNumbers(v, ':', &numbers) || numbers.size() != 2) {
      return Usage("--gnss-outage wants START_S:DURATION_S, got '" + v + "'");
    }
    o.gnss.outages.push_back({numbers[0], numbers[1]});
  }
  if (gnss_quality == "fixed") {
    o.gnss.best_state = slam_mms::sim::GnssState::kRtkFixed;
  } else if (gnss_quality == "float") {
    o.gnss.best_state = slam_mms::sim::GnssState::kRtkFloat;
  } else if (gnss_quality == "sps") {
    o.gnss.best_state = slam_mms::sim::GnssState::kSps;
  }
  const bool origin_given = app.count("--origin") > 0;
  if (origin_given) {
    if (!SplitNumbers(origin, ',', &numbers) || numbers.size() != 3) {
      return Usage("--origin wants LAT,LON,H, got '" + origin + "'");
    }
    o.origin_latitude_deg = numbers[0];
    o.origin_longitude_deg = numbers[1];
    o.origin_height_m = numbers[2];
  }
  if (app.count("--route-variant") > 0 && o.route_variant < 0) {
    return Usage("--route-variant wants K >= 0 (route_variant), got " +
                 std::to_string(o.route_variant));
  }
  if (out.empty()) return Usage("--out DIR is required");
  auto grade = slam_mms::sim::ParseImuGrade(imu_grade);
  if (!grade.ok()) return Usage(grade.status().message());
  const double g = o.gravity_mps2;
  o.imu = DriveSimulator::Options().imu.ForGrade(*grade);
  o.imu.gravity_mps2 = g;
  if (origin_given) o.origin_from_oxts = false;
  if (!o.oxts_drive_dir.empty() && o.oxts_drive_dir.string().size() > 7 &&
      o.oxts_drive_dir.string().substr(o.oxts_drive_dir.string().size() - 7) == ".tar.gz") {
    fs::path unpacked;
    if (!Unpack(o.oxts_drive_dir, &unpacked)) {
      std::cerr << "slam_mms_sim: cannot unpack " << o.oxts_drive_dir << "\n";
      return 1;
    }
    o.oxts_drive_dir = unpacked;
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto sim = DriveSimulator::Create(o);
  if (!sim.ok()) {
    std::cerr << "slam_mms_sim: " << sim.status().ToString() << "\n";
    return 1;
  }
  if (o.route_variant >= 0) {
    std::cerr << "route variant " << o.route_variant << " of "
              << slam_mms::sim::NumRouteVariants(o.scenario) << " (world along all of them), drive "
              << sim->options().drive_id << ", sensor seed " << sim->sensor_seed() << "\n";
  }
  const auto& st = sim->world().stats();
  std::cerr << "world: " << st.num_triangles << " triangles, " << st.num_buildings << " buildings, "
            << st.num_trees << " trees, " << st.num_poles << " poles, " << st.num_cars
            << " parked cars, " << st.num_fences << " fences, " << st.num_hedges << " hedges ("
            << sim->seconds_world_build() << " s)\n";
  auto summary = sim->Run(out, [](int done, int total) {
    if (done % 50 == 0 || done == total) std::cerr << "scan " << done << "/" << total << "\n";
  });
  if (!summary.ok()) {
    std::cerr << "slam_mms_sim: " << summary.status().ToString() << "\n";
    return 1;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("drive: %s\n", summary->drive_dir.c_str());
  std::printf("scans: %d, points: %zu (%.0f per scan), imu records: %d, scene points: %zu\n",
              summary->num_scans, summary->num_points,
              summary->num_points / std::max(1.0, double(summary->num_scans)),
              summary->num_imu_records, summary->num_scene_points);
  std::printf("simulated: %.1f s, %.0f m; gnss fixed %.0f%% float %.0f%% sps %.0f%% none %.0f%%\n",
              summary->simulated_seconds, summary->path_length_m, 100 * summary->fraction_fixed,
              100 * summary->fraction_float, 100 * summary->fraction_sps,
              100 * summary->fraction_none);
  std::printf("wall: %.2f s total (world %.2f s, lidar %.2f s, writing %.2f s); %.2fx real time\n",
              wall, sim->seconds_world_build(), summary->seconds_lidar, summary->seconds_writing,
              summary->simulated_seconds / wall);
  return 0;
}
