// slam_mms_sim: writes a simulated drive in KITTI raw layout with true ground truth.
//
//   slam_mms_sim --scenario default --seed N --duration S --out DIR
//   slam_mms_sim --oxts OXTS_DRIVE_DIR --seed N --duration S --out DIR     (real KITTI motion)
//
// Further options:
//   --gnss-outage START_S:DURATION_S   (repeatable; relative to the first scan)
//   --imu-grade perfect|consumer|tactical|navigation   (default tactical, RT3003-like)
//   --gnss-quality fixed|float|sps     best GNSS solution reachable (default fixed)
//   --urban-canyon SCALE               sky-blockage degradation scale (default 1, 0 = off)
//   --origin LAT,LON,H                 WGS-84 origin of the world frame (default Karlsruhe; with
//                                      --oxts the first record unless --origin is given)
//   --elevation-bias DEG               KITTI-like 0.205 deg low points (default 0)
//   --lead-in S                        IMU/POS records before the first scan (default 1)
//   --threads N (default 2)  --no-scene-cloud  --scene-voxel M  --drive-id N  --date YYYY_MM_DD
// --oxts also accepts a KITTI OXTS archive <drive>_sync.tar.gz (unpacked with `tar` to a temp dir).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/sim/drive_simulator.hpp"

namespace fs = std::filesystem;
using slam_mms::sim::DriveSimulator;

namespace {

int Usage(const std::string& error) {
  if (!error.empty()) std::cerr << "slam_mms_sim: " << error << "\n";
  std::cerr
      << "usage: slam_mms_sim (--scenario default | --oxts OXTS_DRIVE_DIR) --seed N --duration S "
         "--out DIR\n"
         "       [--gnss-outage START_S:DURATION_S]... [--imu-grade "
         "perfect|consumer|tactical|navigation]\n"
         "       [--gnss-quality fixed|float|sps] [--urban-canyon SCALE] [--origin LAT,LON,H]\n"
         "       [--elevation-bias DEG] [--lead-in S] [--threads N] [--no-scene-cloud] "
         "[--scene-voxel M]\n"
         "       [--drive-id N] [--date YYYY_MM_DD]\n";
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

}  // namespace

int main(int argc, char** argv) {
  slam_mms::SetLogSink(slam_mms::StderrLogSink());
  DriveSimulator::Options o;
  fs::path out;
  bool origin_given = false;
  std::string imu_grade = "tactical";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "slam_mms_sim: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    try {
      if (a == "--scenario")
        o.scenario = next();
      else if (a == "--oxts")
        o.oxts_drive_dir = next();
      else if (a == "--seed")
        o.seed = std::stoull(next());
      else if (a == "--duration")
        o.duration_s = std::stod(next());
      else if (a == "--out")
        out = next();
      else if (a == "--gnss-outage") {
        const std::string v = next();
        const size_t c = v.find(':');
        if (c == std::string::npos)
          return Usage("--gnss-outage wants START_S:DURATION_S, got '" + v + "'");
        o.gnss.outages.push_back({std::stod(v.substr(0, c)), std::stod(v.substr(c + 1))});
      } else if (a == "--imu-grade")
        imu_grade = next();
      else if (a == "--gnss-quality") {
        const std::string q = next();
        if (q == "fixed")
          o.gnss.best_state = slam_mms::sim::GnssState::kRtkFixed;
        else if (q == "float")
          o.gnss.best_state = slam_mms::sim::GnssState::kRtkFloat;
        else if (q == "sps")
          o.gnss.best_state = slam_mms::sim::GnssState::kSps;
        else
          return Usage("--gnss-quality must be fixed, float or sps");
      } else if (a == "--urban-canyon")
        o.gnss.urban_canyon_scale = std::stod(next());
      else if (a == "--origin") {
        const std::string v = next();
        double lat, lon, h;
        if (std::sscanf(v.c_str(), "%lf,%lf,%lf", &lat, &lon, &h) != 3)
          return Usage("--origin wants LAT,LON,H");
        o.origin_latitude_deg = lat;
        o.origin_longitude_deg = lon;
        o.origin_height_m = h;
        origin_given = true;
      } else if (a == "--elevation-bias")
        o.lidar.elevation_bias_deg = std::stod(next());
      else if (a == "--lead-in")
        o.lead_in_s = std::stod(next());
      else if (a == "--threads")
        o.num_threads = std::stoi(next());
      else if (a == "--no-scene-cloud")
        o.write_scene_cloud = false;
      else if (a == "--scene-voxel")
        o.scene_cloud_voxel_m = std::stod(next());
      else if (a == "--drive-id")
        o.drive_id = std::stoi(next());
      else if (a == "--date")
        o.date = next();
      else if (a == "-h" || a == "--help")
        return Usage("");
      else
        return Usage("unknown argument '" + a + "'");
    } catch (const std::exception&) {
      return Usage("bad value for " + a);
    }
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
  const auto& st = sim->world().stats();
  std::cerr << "world: " << st.num_triangles << " triangles, " << st.num_buildings << " buildings, "
            << st.num_trees << " trees, " << st.num_poles << " poles, " << st.num_cars
            << " parked cars, " << st.num_fences << " fences (" << sim->seconds_world_build()
            << " s)\n";
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
