#include "slam_mms_sweep/plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

namespace slam_mms::sweep {
namespace fs = std::filesystem;

namespace {

constexpr const char* kScenarioNames[] = {"fixed", "canyon", "float", "sps", "outage"};

std::string WithSync(std::string name) {
  if (name.size() < 5 || name.compare(name.size() - 5, 5, "_sync") != 0) name += "_sync";
  return name;
}

// Single-quoted for /bin/sh.
std::string ShellQuote(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

const char* GnssScenarioName(GnssScenario s) { return kScenarioNames[static_cast<int>(s)]; }

bool ParseGnssScenario(const std::string& name, GnssScenario* s) {
  for (int i = 0; i < 5; ++i) {
    if (name == kScenarioNames[i]) {
      *s = static_cast<GnssScenario>(i);
      return true;
    }
  }
  return false;
}

StatusOr<std::vector<std::string>> ListDrives(const fs::path& oxts_archives) {
  const fs::path index = oxts_archives / "INDEX.tsv";
  std::ifstream in(index);
  if (!in) return NotFoundError("sweep: cannot read " + index.string());
  std::vector<std::string> drives;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line_no == 1 || line.empty()) continue;  // header "drive frames timestamps"
    const std::string name = line.substr(0, line.find('\t'));
    if (name.find("_drive_") == std::string::npos) {
      return DataLossError(index.string() + ":" + std::to_string(line_no) +
                           ": field drive: not a KITTI drive name: '" + name + "'");
    }
    drives.push_back(WithSync(name));
  }
  if (drives.empty()) return DataLossError(index.string() + ": no drive listed");
  return drives;
}

StatusOr<fs::path> UnpackDrive(const fs::path& oxts_archives, const std::string& drive,
                               const fs::path& unpack_dir) {
  const fs::path dir = unpack_dir / drive;
  if (fs::exists(dir / "oxts" / "timestamps.txt")) return dir;
  const fs::path archive = oxts_archives / (drive + ".tar.gz");
  if (!fs::exists(archive)) return NotFoundError("sweep: no archive " + archive.string());
  std::error_code ec;
  fs::create_directories(unpack_dir, ec);
  if (ec) return InternalError("sweep: cannot create " + unpack_dir.string() + ": " + ec.message());
  // tar (GNU, always on Debian) rather than a hand-written gzip/tar reader.
  const std::string cmd =
      "tar -xzf " + ShellQuote(archive.string()) + " -C " + ShellQuote(unpack_dir.string());
  if (std::system(cmd.c_str()) != 0 || !fs::exists(dir / "oxts" / "timestamps.txt")) {
    return DataLossError("sweep: unpacking " + archive.string() + " did not give " +
                         (dir / "oxts").string());
  }
  return dir;
}

StatusOr<MotionStats> WindowMotion(const std::vector<sim::PoseSample>& all,
                                   const std::string& drive, double start_s, double duration_s) {
  if (all.size() < 2) return DataLossError(drive + ": fewer than 2 OXTS records");
  const double t0 = all.front().t_s + start_s, t1 = t0 + duration_s;
  std::vector<const sim::PoseSample*> w;
  for (const sim::PoseSample& p : all) {
    if (p.t_s >= t0 - 1e-9 && p.t_s <= t1 + 1e-9) w.push_back(&p);
  }
  MotionStats m;
  if (w.size() < 2) return m;
  double stationary_s = 0.0, start_path = 0.0, start_time = 0.0;
  for (size_t i = 1; i < w.size(); ++i) {
    const double dt = w[i]->t_s - w[i - 1]->t_s;
    if (!(dt > 0.0)) continue;
    const double d = (w[i]->p_world - w[i - 1]->p_world).norm();
    const double v = d / dt;
    m.path_m += d;
    m.max_speed_mps = std::max(m.max_speed_mps, v);
    if (v < 0.3) stationary_s += dt;
    if (w[i]->t_s - t0 <= 0.5 + 1e-9) {
      start_path += d;
      start_time += dt;
    }
    double dyaw = w[i]->rpy_rad.z() - w[i - 1]->rpy_rad.z();
    dyaw = std::remainder(dyaw, 2.0 * M_PI);
    m.total_turn_deg += std::abs(dyaw) * 180.0 / M_PI;
  }
  const double span = w.back()->t_s - w.front()->t_s;
  m.mean_speed_mps = span > 0.0 ? m.path_m / span : 0.0;
  m.start_speed_mps = start_time > 0.0 ? start_path / start_time : 0.0;
  m.stationary_fraction = span > 0.0 ? stationary_s / span : 1.0;
  for (size_t i = 0, j = 0; i < w.size(); ++i) {
    while (j < w.size() && w[j]->t_s - w[i]->t_s < 0.5 - 1e-9) ++j;
    if (j >= w.size()) break;
    const double dyaw = std::remainder(w[j]->rpy_rad.z() - w[i]->rpy_rad.z(), 2.0 * M_PI);
    m.max_yaw_rate_dps =
        std::max(m.max_yaw_rate_dps, std::abs(dyaw) * 180.0 / M_PI / (w[j]->t_s - w[i]->t_s));
  }
  std::vector<std::string> classes;
  if (m.path_m < 1.0) {
    classes.push_back("standing");
  } else if (m.stationary_fraction >= 0.1) {
    classes.push_back("stop-and-go");
  }
  if (m.mean_speed_mps >= 18.0) classes.push_back("highway");
  if (m.start_speed_mps >= 8.0) classes.push_back("start-at-speed");
  if (m.max_yaw_rate_dps >= 15.0) classes.push_back("sharp-turn");
  if (drive.rfind("2011_09_28", 0) == 0) classes.push_back("campus");
  if (classes.empty()) classes.push_back("city");
  std::vector<sim::PoseSample> window;
  for (const sim::PoseSample* p : w) window.push_back(*p);
  if (!sim::FindImplausibleMotion(window).empty()) classes.push_back("not-a-car");
  for (size_t i = 0; i < classes.size(); ++i) m.classes += (i ? "+" : "") + classes[i];
  return m;
}

void CalibrationErrorDraw(uint64_t seed, const Eigen::Vector3d& sigma_rpy_deg,
                          const Eigen::Vector3d& sigma_xyz_m,
                          const Eigen::Vector3d& sigma_mount_rpy_deg, Eigen::Vector3d* rpy_deg,
                          Eigen::Vector3d* xyz_m, Eigen::Vector3d* mount_rpy_deg) {
  // Its own stream (not the simulator's, which is seeded by `seed` too).
  std::mt19937_64 gen(seed * 0x9E3779B97F4A7C15ull + 0x63616C6962ull);
  const auto normal = [&gen]() {
    const double u1 = (static_cast<double>(gen() >> 11) + 0.5) * 0x1.0p-53;  // (0, 1)
    const double u2 = static_cast<double>(gen() >> 11) * 0x1.0p-53;
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  };
  const auto draw = [&normal](double sigma, double limit) {
    const double z = std::clamp(normal(), -3.0, 3.0);  // drawn even where sigma is 0
    return sigma > 0.0 ? std::clamp(z * sigma, -limit, limit) : 0.0;
  };
  for (int i = 0; i < 3; ++i) (*rpy_deg)(i) = draw(sigma_rpy_deg(i), 10.0);
  for (int i = 0; i < 3; ++i) (*xyz_m)(i) = draw(sigma_xyz_m(i), 1.0);
  for (int i = 0; i < 3; ++i) (*mount_rpy_deg)(i) = draw(sigma_mount_rpy_deg(i), 10.0);
}

StatusOr<std::vector<SweepRun>> BuildPlan(const PlanOptions& o) {
  if (!(o.duration_s > 0.0)) return InvalidArgumentError("sweep: --duration must be > 0");
  if (o.runs_per_drive < 1) return InvalidArgumentError("sweep: --runs-per-drive must be >= 1");
  if (o.scenarios.empty()) return InvalidArgumentError("sweep: no GNSS scenario");
  SLAM_MMS_ASSIGN_OR_RETURN(std::vector<std::string> listed, ListDrives(o.oxts_archives));
  std::vector<std::string> drives;
  if (o.drives.empty()) {
    drives = listed;
  } else {
    for (const std::string& d : o.drives) {
      const std::string name = WithSync(d);
      if (std::find(listed.begin(), listed.end(), name) == listed.end()) {
        return NotFoundError("sweep: drive '" + d + "' is not in " +
                             (o.oxts_archives / "INDEX.tsv").string());
      }
      drives.push_back(name);
    }
  }
  if (o.max_drives > 0 && static_cast<int>(drives.size()) > o.max_drives) {
    drives.resize(o.max_drives);
  }
  std::vector<SweepRun> runs;
  for (size_t d = 0; d < drives.size(); ++d) {
    SLAM_MMS_ASSIGN_OR_RETURN(fs::path dir, UnpackDrive(o.oxts_archives, drives[d], o.unpack_dir));
    SLAM_MMS_ASSIGN_OR_RETURN(sim::OxtsPoseSamples loaded,
                              sim::LoadOxtsPoseSamples(dir, 0.0, 0.0, 0.0, true));
    if (loaded.samples.size() < 4) {
      return DataLossError(dir.string() + ": fewer than 4 usable OXTS records");
    }
    const double span = loaded.samples.back().t_s - loaded.samples.front().t_s;
    // The window: lead-in, the scans, and the simulator's end margin (0.05 s + one sweep).
    const double need = o.lead_in_s + o.duration_s + 0.3;
    const double free_s = std::max(0.0, span - need);
    const double duration = std::min(o.duration_s, std::max(0.5, span - o.lead_in_s - 0.3));
    // The drive's place in INDEX.tsv (not in the selection): a run is the same whichever drives
    // are selected, so that `--drives D` reproduces one run of a whole sweep.
    const size_t k =
        static_cast<size_t>(std::find(listed.begin(), listed.end(), drives[d]) - listed.begin());
    for (int r = 0; r < o.runs_per_drive; ++r) {
      static constexpr double kPlacement[] = {0.0, 0.5, 1.0};
      SweepRun run;
      run.drive = drives[d];
      run.oxts_dir = dir;
      run.oxts_start_s = std::floor(kPlacement[(k + r) % 3] * free_s * 10.0) / 10.0;
      run.duration_s = duration;
      run.seed = 10 * k + r + 1;
      run.scenario = o.scenarios[(k + r) % o.scenarios.size()];
      if (run.scenario == GnssScenario::kOutage) {
        run.outage = std::make_pair(0.3 * duration, 0.4 * duration);
      }
      CalibrationErrorDraw(run.seed, o.calib_error_sigma_rpy_deg, o.calib_error_sigma_xyz_m,
                           o.imu_mount_error_sigma_rpy_deg, &run.calib_error_rpy_deg,
                           &run.calib_error_xyz_m, &run.imu_mount_error_rpy_deg);
      SLAM_MMS_ASSIGN_OR_RETURN(run.motion, WindowMotion(loaded.samples, run.drive,
                                                         run.oxts_start_s + o.lead_in_s, duration));
      std::string short_name = run.drive.substr(0, run.drive.size() - 5);  // without _sync
      run.id = short_name + "_r" + std::to_string(r) + "_" + GnssScenarioName(run.scenario);
      runs.push_back(std::move(run));
    }
  }
  if (o.ci_subset) {
    std::vector<SweepRun> subset;
    for (const char* cls :
         {"standing", "stop-and-go", "highway", "start-at-speed", "sharp-turn", "campus", "city"}) {
      for (const SweepRun& r : runs) {
        const std::string c = "+" + r.motion.classes + "+";
        const bool taken = std::any_of(subset.begin(), subset.end(),
                                       [&](const SweepRun& s) { return s.id == r.id; });
        if (!taken && c.find(std::string("+") + cls + "+") != std::string::npos) {
          subset.push_back(r);
          break;
        }
      }
    }
    runs = std::move(subset);
  }
  return runs;
}

}  // namespace slam_mms::sweep
