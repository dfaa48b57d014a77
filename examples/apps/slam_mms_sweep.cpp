// slam_mms_sweep: the robustness sweep (issue 15). Simulates drives along windows of every real
// KITTI motion in <data>/kitti_oxts (several seeds, GNSS scenarios and outage placements), runs
// every mapping method on each exactly as slam_mms_run does, and writes one table with a
// pass/fail column per rule (slam_mms_sweep/rules.hpp), plus the real-frame lidar_only check.
//
//   slam_mms_sweep --out DIR [--data DIR] [--drives D1,D2,...] [--max-drives N]
//                  [--runs-per-drive R] [--duration S] [--scenarios fixed,canyon,outage,float,sps]
//                  [--modes gnss_ins,gnss_ins_smoothed,full,lidar_only] [--subset ci]
//                  [--jobs N] [--timeout S] [--config FILE] [--rerun] [--keep-drives]
//                  [--no-real] [--fail-on rules|sanity|never]
//                  [--calib-error-sigma-rpy-deg R,P,Y] [--calib-error-sigma-xyz-m X,Y,Z]
//                  [--imu-mount-error-sigma-rpy-deg R,P,Y]
//
// The last three write each run's calibration file wrong, or mount its IMU off the car's axes,
// by a draw from N(0, sigma) per axis from the run's seed (plan.hpp, CalibrationErrorDraw); a
// --config with drive.estimate_extrinsics: true runs the boresight self-calibration first.
// Each run is a child process (slam_mms_sweep --run-one DIR/runs/<id>), so a crash or a hang
// (killed after --timeout) fails that run's `sane` rule and the sweep goes on. A run whose
// result.json exists for the same spec and the same executable is reused (a killed sweep
// continues where it was; --rerun runs everything again). Runs start interleaved (every fourth
// first), so that a sweep stopped early still spans the drive list. Outputs: DIR/sweep.md,
// sweep.csv, sweep.json, runs/<id>/{spec.json, result.json, log.txt}. Exit: 0 every rule passed, 1
// some rule failed (--fail-on rules) or a run was not sane (--fail-on sanity), 2 bad command line,
// 3 the sweep itself failed.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "app_common/huge_page_malloc.hpp"
#include "slam_mms/version.hpp"
#include "slam_mms_run/json_file.hpp"
#include "slam_mms_sweep/plan.hpp"
#include "slam_mms_sweep/rules.hpp"
#include "slam_mms_sweep/run_one.hpp"

extern char** environ;

namespace {
namespace fs = std::filesystem;
using Json = nlohmann::json;
using namespace slam_mms::sweep;

std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop.store(true); }

// result.json or spec.json, or null where it is missing or unreadable (the run then runs again).
Json ReadJsonOrNull(const fs::path& p) {
  slam_mms::StatusOr<Json> j = slam_mms::app::ReadJsonFile(p);
  return j.ok() ? *j : Json(nullptr);
}

struct Child {
  pid_t pid = -1;
  size_t index = 0;
  std::chrono::steady_clock::time_point start;
};

// Starts `self args...` with stdout and stderr into `log`.
pid_t Spawn(const std::string& self, const std::vector<std::string>& args, const fs::path& log) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  std::vector<std::string> all = {self};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, self.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  return rc == 0 ? pid : -1;
}

std::string DescribeExit(int status) {
  if (WIFEXITED(status)) {
    return WEXITSTATUS(status) == 0 ? "" : "exit " + std::to_string(WEXITSTATUS(status));
  }
  if (WIFSIGNALED(status)) return "crash: signal " + std::to_string(WTERMSIG(status));
  return "unknown end";
}

// Runs `jobs` child processes at a time; fills records[i].process_error / wall_s.
void RunChildren(const std::string& self, const std::vector<std::vector<std::string>>& args,
                 const std::vector<fs::path>& logs, int jobs, double timeout_s,
                 std::vector<RunRecord>* records, const std::vector<size_t>& todo) {
  std::vector<Child> running;
  size_t next = 0;
  size_t done = 0;
  while ((next < todo.size() && !g_stop.load()) || !running.empty()) {
    while (!g_stop.load() && next < todo.size() && static_cast<int>(running.size()) < jobs) {
      const size_t i = todo[next++];
      Child c;
      c.index = i;
      c.start = std::chrono::steady_clock::now();
      c.pid = Spawn(self, args[i], logs[i]);
      if (c.pid < 0) {
        (*records)[i].process_error = "could not start the run's process";
        continue;
      }
      running.push_back(c);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    for (size_t k = 0; k < running.size();) {
      Child& c = running[k];
      int status = 0;
      const pid_t w = waitpid(c.pid, &status, WNOHANG);
      const double elapsed =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - c.start).count();
      RunRecord& rec = (*records)[c.index];
      if (w == c.pid) {
        rec.process_error = DescribeExit(status);
        rec.wall_s = elapsed;
      } else if (elapsed > timeout_s) {
        kill(c.pid, SIGKILL);
        waitpid(c.pid, &status, 0);
        rec.process_error =
            "hang: killed after " + std::to_string(static_cast<int>(timeout_s)) + " s (--timeout)";
        rec.wall_s = elapsed;
      } else {
        ++k;
        continue;
      }
      ++done;
      const std::string id =
          rec.spec.contains("id") ? rec.spec["id"].get<std::string>() : std::string("real frames");
      std::printf("[sweep] %zu/%zu %s: %s (%.0f s)\n", done, todo.size(), id.c_str(),
                  rec.process_error.empty() ? "done" : rec.process_error.c_str(), elapsed);
      std::fflush(stdout);
      running.erase(running.begin() + static_cast<long>(k));
    }
  }
}

int Usage(const std::string& error) {
  std::fprintf(stderr, "slam_mms_sweep: %s (see --help)\n", error.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  slam_mms::app::ReexecWithHugePageMalloc(argv);  // the child runs inherit it
  // The child modes.
  if (argc >= 3 && std::string(argv[1]) == "--run-one") return RunOne(argv[2]);
  if (argc >= 4 && std::string(argv[1]) == "--real-one") {
    return RealOne(argv[2], argv[3], argc >= 5 ? fs::path(argv[4]) : fs::path());
  }

  CLI::App app("slam_mms_sweep: the robustness sweep over real KITTI motions (issue 15)",
               "slam_mms_sweep");
  fs::path out, data, config;
  std::vector<std::string> drives, scenarios = {"fixed", "canyon", "outage", "float", "sps"},
                                   modes = {"gnss_ins", "gnss_ins_smoothed", "full", "lidar_only"};
  std::string subset, fail_on = "rules";
  PlanOptions plan;
  int jobs = 1;
  double timeout_s = 1800.0;
  bool rerun = false, keep = false, no_real = false, version = false;
  app.add_option("--out", out, "output folder (created)");
  app.add_option("--data", data,
                 "the shared data folder (kitti_oxts/, kitti_raw/); default "
                 "$SLAM_MMS_SHARED_DATA, else ../shared/data");
  app.add_option("--drives", drives, "comma-separated drives (default: all in INDEX.tsv)")
      ->delimiter(',');
  app.add_option("--max-drives", plan.max_drives, "only the first N drives");
  app.add_option("--runs-per-drive", plan.runs_per_drive, "windows x seeds per drive (default 1)");
  app.add_option("--duration", plan.duration_s, "seconds of scans per run (default 12)");
  app.add_option("--scenarios", scenarios, "GNSS scenarios cycled over the drives")->delimiter(',');
  app.add_option("--modes", modes, "methods run on each drive")->delimiter(',');
  app.add_option("--subset", subset, "ci: only the first run of each motion class")
      ->check(CLI::IsMember({"ci"}));
  app.add_option("--jobs", jobs, "runs at a time (default 1; each uses 2 threads)");
  app.add_option("--timeout", timeout_s, "seconds before a run counts as hung (default 1800)");
  app.add_option("--config", config, "a slam_mms_run --config YAML for every run");
  app.add_flag("--rerun", rerun, "run again runs that have a result for the same spec");
  app.add_flag("--keep-drives", keep, "keep each run's simulated drive");
  app.add_flag("--no-real", no_real, "skip the real-frame lidar_only check");
  app.add_option("--fail-on", fail_on,
                 "rules (default): exit 1 on any failed rule; sanity: only on a run that is "
                 "not sane; never")
      ->check(CLI::IsMember({"rules", "sanity", "never"}));
  std::vector<double> calib_sigma_rpy, calib_sigma_xyz;
  app.add_option("--calib-error-sigma-rpy-deg", calib_sigma_rpy,
                 "roll,pitch,yaw: each run's calibration file is written with a boresight error "
                 "drawn from N(0, sigma) per axis (default 0: the true calibration)")
      ->delimiter(',')
      ->expected(3);
  app.add_option("--calib-error-sigma-xyz-m", calib_sigma_xyz,
                 "x,y,z: the same for the lever arm [m]")
      ->delimiter(',')
      ->expected(3);
  std::vector<double> mount_sigma_rpy;
  app.add_option("--imu-mount-error-sigma-rpy-deg", mount_sigma_rpy,
                 "roll,pitch,yaw: each run's IMU is mounted rotated against the car by a draw "
                 "from N(0, sigma) per axis (default 0: along the car)")
      ->delimiter(',')
      ->expected(3);
  app.add_flag("--version", version);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (version) {
    std::printf("slam_mms_sweep %s\n", SLAM_MMS_VERSION_STRING);
    return 0;
  }
  if (out.empty()) return Usage("--out DIR is required");
  if (jobs < 1) return Usage("--jobs must be >= 1");
  if (!(timeout_s > 0)) return Usage("--timeout must be > 0");
  if (data.empty()) {
    const char* env = std::getenv("SLAM_MMS_SHARED_DATA");
    data = env != nullptr && *env != '\0' ? fs::path(env) : fs::path("../shared/data");
  }
  plan.oxts_archives = data / "kitti_oxts";
  if (!fs::exists(plan.oxts_archives / "INDEX.tsv")) {
    std::fprintf(stderr, "slam_mms_sweep: input absent, skipped: no %s\n",
                 (plan.oxts_archives / "INDEX.tsv").c_str());
    return 77;
  }
  plan.drives = drives;
  plan.scenarios.clear();
  for (const std::string& s : scenarios) {
    GnssScenario g;
    if (!ParseGnssScenario(s, &g)) return Usage("--scenarios: unknown scenario '" + s + "'");
    plan.scenarios.push_back(g);
  }
  plan.ci_subset = subset == "ci";
  // Each sigma of a --*-sigma-* option in [0, max].
  const auto sigmas = [](const std::vector<double>& given, double max, Eigen::Vector3d* out) {
    for (size_t i = 0; i < given.size(); ++i) {
      if (!(given[i] >= 0.0 && given[i] <= max)) return false;
      (*out)(i) = given[i];
    }
    return true;
  };
  if (!sigmas(calib_sigma_rpy, 3.0, &plan.calib_error_sigma_rpy_deg)) {
    return Usage("--calib-error-sigma-rpy-deg: each sigma in [0, 3] deg");
  }
  if (!sigmas(calib_sigma_xyz, 0.3, &plan.calib_error_sigma_xyz_m)) {
    return Usage("--calib-error-sigma-xyz-m: each sigma in [0, 0.3] m");
  }
  if (!sigmas(mount_sigma_rpy, 3.0, &plan.imu_mount_error_sigma_rpy_deg)) {
    return Usage("--imu-mount-error-sigma-rpy-deg: each sigma in [0, 3] deg");
  }
  RunSettings settings;
  settings.modes = modes;
  settings.config = config.empty() ? fs::path() : fs::absolute(config);
  settings.keep_drive = keep;
  std::error_code ec;
  fs::create_directories(out / "runs", ec);
  if (ec) return Usage("--out: cannot create " + (out / "runs").string() + ": " + ec.message());
  out = fs::absolute(out);
  plan.unpack_dir = out / "oxts";

  const auto t0 = std::chrono::steady_clock::now();
  slam_mms::StatusOr<std::vector<SweepRun>> runs = BuildPlan(plan);
  if (!runs.ok()) {
    std::fprintf(stderr, "slam_mms_sweep: %s\n", runs.status().ToString().c_str());
    return runs.status().code() == slam_mms::StatusCode::kInvalidArgument ||
                   runs.status().code() == slam_mms::StatusCode::kNotFound
               ? 2
               : 3;
  }
  std::string mode_list;
  for (const std::string& m : modes) mode_list += (mode_list.empty() ? "" : ",") + m;
  std::printf("[sweep] %zu runs planned (%.1f s each, modes %s)\n", runs->size(), plan.duration_s,
              mode_list.c_str());

  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  // Specs, reuse of finished runs, then the children.
  const std::string self = fs::canonical("/proc/self/exe").string();
  // The executable's identity in every spec: a result of another build is never reused.
  std::string binary = self;
  {
    std::error_code e1, e2;
    const auto size = fs::file_size(self, e1);
    const auto mtime = fs::last_write_time(self, e2).time_since_epoch().count();
    binary += " " + std::to_string(e1 ? 0 : size) + " " + std::to_string(e2 ? 0 : mtime);
  }
  // One record, folder and child command line per run; the last slot is the real frames'.
  const size_t n = runs->size();
  std::vector<RunRecord> records(n + 1);
  std::vector<fs::path> dirs(n + 1);
  std::vector<std::vector<std::string>> args(n + 1);
  std::vector<size_t> todo;
  for (size_t i = 0; i < n; ++i) {
    dirs[i] = out / "runs" / (*runs)[i].id;
    fs::create_directories(dirs[i], ec);
    records[i].spec = SpecToJson((*runs)[i], settings);
    records[i].spec["binary"] = binary;
    const Json old = ReadJsonOrNull(dirs[i] / "result.json");
    if (!rerun && old.is_object() && old.contains("methods") && old["spec"] == records[i].spec) {
      records[i].result = old;
      continue;
    }
    fs::remove(dirs[i] / "result.json", ec);
    const slam_mms::Status spec_written =
        slam_mms::app::WriteJsonFile(records[i].spec, dirs[i] / "spec.json", 2);
    if (!spec_written.ok()) {
      records[i].process_error = spec_written.ToString();
      continue;
    }
    args[i] = {"--run-one", dirs[i].string()};
    todo.push_back(i);
  }
  // Interleaved order (every 4th run first): a sweep stopped early still covers the whole list.
  std::stable_sort(todo.begin(), todo.end(), [](size_t a, size_t b) { return a % 4 < b % 4; });
  std::printf("[sweep] %zu to run, %zu reused from earlier sweeps\n", todo.size(), n - todo.size());
  // The real frames (issue 15: lidar_only drift on real data vs the public peer), run last.
  const fs::path real_drive = data / "kitti_raw" / "2011_09_26" / "2011_09_26_drive_0013_sync";
  const bool with_real = !no_real && fs::exists(real_drive);
  if (with_real) {
    dirs[n] = out / "runs" / "real_2011_09_26_drive_0013";
    fs::create_directories(dirs[n], ec);
    fs::remove(dirs[n] / "result.json", ec);
    args[n] = {"--real-one", dirs[n].string(), real_drive.string()};
    if (!settings.config.empty()) args[n].push_back(settings.config.string());
    todo.push_back(n);
  }
  std::vector<fs::path> logs(n + 1);
  for (const size_t i : todo) logs[i] = dirs[i] / "log.txt";
  RunChildren(self, args, logs, jobs, timeout_s, &records, todo);
  for (const size_t i : todo) records[i].result = ReadJsonOrNull(dirs[i] / "result.json");
  // An interrupted sweep's tables hold the runs that finished (the others are counted).
  std::vector<RunRecord> finished;
  size_t not_run = 0;
  for (size_t i = 0; i < n; ++i) {
    const bool ran = !records[i].result.is_null() || !records[i].process_error.empty();
    if (g_stop.load() && !ran) {
      ++not_run;
      continue;
    }
    finished.push_back(records[i]);
  }

  std::string command;
  for (int i = 0; i < argc; ++i) command += (i ? " " : "") + std::string(argv[i]);
  int failures = 0;
  const slam_mms::Status written =
      WriteSweepTables(finished, with_real ? &records[n] : nullptr, command, out, &failures);
  if (!written.ok()) {
    std::fprintf(stderr, "slam_mms_sweep: %s\n", written.ToString().c_str());
    return 3;
  }
  int insane = 0;
  for (const RunRecord& r : finished) {
    if (EvaluateRules(r).front().verdict != "pass") ++insane;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[sweep] %zu runs, %d rule failures (%d runs not sane), %.0f s; table in %s\n",
              finished.size(), failures, insane, wall, (out / "sweep.md").c_str());
  if (g_stop.load()) {
    std::printf("[sweep] interrupted: the tables hold the %zu runs finished, %zu were not run\n",
                finished.size(), not_run);
    return 130;
  }
  if (fail_on == "rules" && failures > 0) return 1;
  if (fail_on == "sanity" && insane > 0) return 1;
  return 0;
}
