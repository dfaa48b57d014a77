// slam_mms_run, the main job (issue 8), as app::RunMain: slam_mms_run's main() and the Python
// package's `python -m slam_mms run` both call it. A drive in (KITTI raw, a plain folder, a ROS 1
// bag, or the embedded demo drive, simulated first); per method (full, gnss_ins,
// gnss_ins_smoothed, lidar_only) trajectories, maps and geo-referenced files out, evaluated against
// the ground truth (the simulator's, else OXTS) in report.json, plots, report.html and a summary
// table. The flags are in cli.hpp and docs/user_guide.md.
//
// Errors: a scan that cannot be read is skipped with a warning naming its file; any other input or
// processing error stops the run with a message naming file/line/field, after everything computed
// so far is written (trajectories, maps, report with what exists); exit status 1. A bad command
// line or config file: exit status 2, before any work. SIGINT/SIGTERM: the run stops after the
// current scan, writes what was computed ("complete": false) and exits 128 + signal.

#include "slam_mms_run/run_main.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/drive/open_drive.hpp"
#include "slam_mms/eval/ground_truth.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/eval/report.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/io/map_io.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms/merge/drive_result_io.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"
#include "slam_mms/pipeline/sensor_presets.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms/version.hpp"
#include "slam_mms_run/calibration.hpp"
#include "slam_mms_run/checkpoint.hpp"
#include "slam_mms_run/cli.hpp"
#include "slam_mms_run/config_file.hpp"
#include "slam_mms_run/geo_outputs.hpp"
#include "slam_mms_run/input.hpp"
#include "slam_mms_run/outputs.hpp"
#include "slam_mms_run/plot_outputs.hpp"
#include "slam_mms_run/progress.hpp"
#include "slam_mms_run/run_mode.hpp"
#include "slam_mms_run/run_report.hpp"

namespace slam_mms::app {

namespace fs = std::filesystem;

namespace {

constexpr int kExitError = 1;
constexpr int kExitUsage = 2;
// localizer.spill_dir's app default: the --out folder (see main).
const fs::path kSpillToOutDir = "<out>";

// SIGINT / SIGTERM: the first one sets the flag that RunDrive and the simulator poll before every
// scan (the run then ends after the current scan, writes everything computed so far and exits
// 128 + signal). A second one more than a second later ends the process at once; repeats within
// the second are the same request delivered twice (`timeout` signals its child and then its
// process group) and are ignored.
std::atomic<bool> g_stop{false};
volatile std::sig_atomic_t g_signal = 0;
timespec g_first_signal{};
static_assert(std::atomic<bool>::is_always_lock_free, "the stop flag is set in a signal handler");

extern "C" void OnStopSignal(int sig) {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);  // async-signal-safe
  if (!g_stop.load()) {
    g_first_signal = now;
    g_signal = sig;
    g_stop.store(true);
    return;
  }
  const double since = static_cast<double>(now.tv_sec - g_first_signal.tv_sec) +
                       1e-9 * static_cast<double>(now.tv_nsec - g_first_signal.tv_nsec);
  if (since > 1.0) {
    signal(sig, SIG_DFL);
    raise(sig);
  }
}

// Installs the stop handlers for one RunMain call and puts the previous ones (and the previous
// log sink) back at its end: RunMain also runs inside a Python process (python -m slam_mms run).
class StopHandlers {
 public:
  StopHandlers() {
    g_stop.store(false);
    g_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = OnStopSignal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~StopHandlers() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  StopHandlers(const StopHandlers&) = delete;
  StopHandlers& operator=(const StopHandlers&) = delete;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

class LogSinkGuard {
 public:
  LogSinkGuard() : previous_(InstallLogSink()) {}
  ~LogSinkGuard() { SetLogSink(previous_); }
  LogSinkGuard(const LogSinkGuard&) = delete;
  LogSinkGuard& operator=(const LogSinkGuard&) = delete;

 private:
  LogSink previous_;
};

int StopExitCode() { return 128 + static_cast<int>(g_signal); }
const char* StopSignalName() { return g_signal == SIGTERM ? "SIGTERM" : "SIGINT"; }

// --out is created and a file written into it before any work, so that a folder that cannot be
// written fails at once instead of after the run.
Status CheckOutputDir(const fs::path& dir) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
    return InvalidArgumentError("--out " + dir.string() + ": exists and is not a folder");
  }
  fs::create_directories(dir, ec);
  if (ec) {
    return InvalidArgumentError("--out " + dir.string() +
                                ": cannot create the folder: " + ec.message());
  }
  if (!fs::is_directory(dir, ec)) {
    return InvalidArgumentError("--out " + dir.string() + ": exists and is not a folder");
  }
  const fs::path probe = dir / (".slam_mms_write_probe_" + std::to_string(::getpid()));
  errno = 0;
  bool written = false;
  {
    std::ofstream f(probe, std::ios::binary | std::ios::trunc);
    if (f) f << "slam_mms\n";
    f.flush();
    written = static_cast<bool>(f);
  }
  const int err = errno;
  fs::remove(probe, ec);
  if (!written) {
    return InvalidArgumentError("--out " + dir.string() +
                                ": not writable (cannot create a file in it" +
                                (err != 0 ? std::string(": ") + std::strerror(err) : "") + ")");
  }
  return OkStatus();
}

int Fail(const Status& status, int code) {
  ProgressReporter::BreakLine();
  std::fprintf(stderr, "slam_mms_run: error: %s\n", status.message().c_str());
  return code;
}

// Simulates the embedded drive (--sim-scenario, "demo" by default) into out/sim; returns the drive
// folder. Stopped by a signal: the drive is left as written so far and *stopped is set.
StatusOr<fs::path> SimulateDefaultDrive(const RunArgs& args, bool tty, bool* stopped) {
  sim::DriveSimulator::Options so;
  so.scenario = args.sim_scenario;
  so.duration_s = args.sim_duration_s;
  so.seed = args.sim_seed;
  std::printf("[sim] simulating the %s drive (%s, seed %llu) into %s\n", args.sim_scenario.c_str(),
              args.sim_duration_s > 0 ? (std::to_string(args.sim_duration_s) + " s").c_str()
                                      : "whole route",
              static_cast<unsigned long long>(args.sim_seed), (args.out_dir / "sim").c_str());
  std::fflush(stdout);
  SLAM_MMS_ASSIGN_OR_RETURN(sim::DriveSimulator simulator, sim::DriveSimulator::Create(so));
  ProgressReporter progress("sim", static_cast<size_t>(simulator.num_scans()), tty);
  SLAM_MMS_ASSIGN_OR_RETURN(
      const sim::DriveSimulator::Summary summary,
      simulator.Run(
          args.out_dir / "sim", [&](int done, int) { progress.Update(done); }, &g_stop));
  *stopped = summary.stopped;
  char note[160];
  std::snprintf(note, sizeof(note), "(%.0f m, %.1f s simulated)", summary.path_length_m,
                summary.simulated_seconds);
  progress.Finish(static_cast<size_t>(summary.num_scans), note);
  return summary.drive_dir;
}

// The drive a killed run simulated into `sim_dir` (its ground_truth/scenario.json, the
// simulator's last file, exists); empty when there is none.
fs::path CompleteSimulatedDrive(const fs::path& sim_dir) {
  std::error_code ec;
  for (fs::directory_iterator date(sim_dir, ec), end; !ec && date != end; date.increment(ec)) {
    std::error_code e2;
    for (fs::directory_iterator d(date->path(), e2), end2; !e2 && d != end2; d.increment(e2)) {
      std::error_code e3;
      if (fs::exists(d->path() / "ground_truth" / "scenario.json", e3)) return d->path();
    }
  }
  return {};
}

// What makes two runs the same run (checkpoint.hpp): each value a JSON text.
RunFingerprint MakeFingerprint(const RunArgs& args, const fs::path& input,
                               const std::string& options_json) {
  auto quote = [](const std::string& s) {
    std::string q = "\"";
    for (const char c : s) {
      if (c == '"' || c == '\\') q += '\\';
      q += c;
    }
    return q + "\"";
  };
  RunFingerprint f;
  std::error_code ec;
  f["input"] = input.empty() ? quote("simulated") : quote(fs::absolute(input, ec).string());
  f["frames"] =
      "[" + std::to_string(args.first_frame) + ", " + std::to_string(args.last_frame) + "]";
  f["topics"] = "[" + quote(args.lidar_topic) + ", " + quote(args.imu_topic) + ", " +
                quote(args.gnss_topic) + "]";
  f["extrinsics"] = quote(args.extrinsics.string());
  f["imu_noise"] = quote(args.imu_noise.string());
  if (args.kitti_vertical_correction_deg != 0.0) {
    char v[40];
    std::snprintf(v, sizeof(v), "%.17g", args.kitti_vertical_correction_deg);
    f["kitti_vertical_correction_deg"] = v;
  }
  if (args.kitti_oxts_inertial_delay_s) {
    char v[40];
    std::snprintf(v, sizeof(v), "%.17g", *args.kitti_oxts_inertial_delay_s);
    f["kitti_oxts_inertial_delay_s"] = v;
  }
  f["options"] = options_json;
  std::string outages = "[";
  for (const auto& [start, duration] : args.gnss_outages) {
    char w[80];
    std::snprintf(w, sizeof(w), "%s[%.17g, %.17g]", outages.size() > 1 ? ", " : "", start,
                  duration);
    outages += w;
  }
  f["gnss_outages"] = outages + "]";
  f["pos"] = quote(PosWorkflowName(args.pos));
  if (input.empty()) {
    char sim[160];
    std::snprintf(sim, sizeof(sim), "[%s, %llu, %.17g]", quote(args.sim_scenario).c_str(),
                  static_cast<unsigned long long>(args.sim_seed), args.sim_duration_s);
    f["sim"] = sim;
  }
  return f;
}

// The input line and the warnings about outage windows outside the drive.
void AnnounceInput(const DriveReader& reader, const RunArgs& args, const std::string& gt_kind,
                   double duration_s, const std::function<void(const std::string&)>& warn) {
  const DriveStreams& streams = reader.streams();
  std::printf(
      "[input] %s: %zu scans, %.1f s, IMU %zu samples, GNSS %zu fixes%s, ground truth: %s\n",
      reader.Describe().c_str(), reader.NumScans(), duration_s, streams.imu.size(),
      streams.gnss.size(),
      streams.pos.empty()
          ? ""
          : (", external POS " + std::to_string(streams.pos.size()) + " records").c_str(),
      gt_kind.c_str());
  for (const auto& [start, duration] : args.gnss_outages) {
    std::printf("[input] GNSS outage %.1f s .. %.1f s after the first scan\n", start,
                start + duration);
    char text[256];
    if (start >= duration_s) {
      std::snprintf(text, sizeof(text),
                    "--gnss-outage %g:%g starts after the drive's last scan (%.1f s): it removes "
                    "no GNSS fix",
                    start, duration, duration_s);
      warn(text);
    } else if (start + duration > duration_s) {
      std::snprintf(text, sizeof(text),
                    "--gnss-outage %g:%g ends after the drive's last scan (%.1f s): the outage is "
                    "%.1f s long, not %g s",
                    start, duration, duration_s, duration_s - start, duration);
      warn(text);
    }
  }
}

// Every method in turn (those a --resume finds finished are read back); each method's files are
// written as soon as it ends, its map entropy computed beside the writing. A method's or a
// file's error goes to *fatal and stops the loop; the returned error (a finished method that cannot
// be read back) ends the run at once.
Status RunMethods(const RunArgs& args, const MappingSystem::Options& options,
                  const DriveReader& reader, bool tty, Checkpoint* checkpoint,
                  GeoOutputOptions* geo, const std::function<void(const std::string&)>& warn,
                  std::vector<ModeRun>* runs, Status* fatal) {
  for (const MappingMode mode : args.modes) {
    if (g_stop.load()) break;
    const std::string name = MappingModeName(mode);
    if (args.resume && checkpoint->HasFinished(name)) {
      // Finished before the run was killed: its files are in --out; read it back for the report.
      StatusOr<ModeRun> loaded = checkpoint->LoadFinished(name);
      if (!loaded.ok()) return loaded.status();
      std::printf("[%s] finished in the checkpointed run: %zu poses read back\n", name.c_str(),
                  loaded->trajectory.size());
      if (loaded->origin && !geo->run_origin) geo->run_origin = loaded->origin;
      runs->push_back(std::move(loaded).value());
      continue;
    }
    // Every --checkpoint-every finished submaps: the trajectory so far and the progress.
    auto on_submap = [&](const MappingSystem& system, int submaps) {
      if (args.checkpoint_every_submaps <= 0 || submaps % args.checkpoint_every_submaps != 0) {
        return;
      }
      Status s = WriteTrajectoryTum(system.FinalTrajectory(), args.out_dir / (name + ".tum"));
      if (s.ok()) s = checkpoint->SaveProgress(name, system.results().size(), submaps);
      if (!s.ok()) {
        SLAM_MMS_LOG(kWarning) << "checkpoint: " << s.ToString();
      }
    };
    // --drive-result: the full method's submaps, clouds and level-2 factors (slam_mms_merge).
    Status drive_result = OkStatus();
    std::function<void(const MappingSystem&)> on_finished;
    if (args.drive_result && mode == MappingMode::kFull) {
      on_finished = [&](const MappingSystem& system) {
        StatusOr<DriveResult> r = system.ExportDriveResult();
        drive_result = r.ok() ? WriteDriveResult(*r, args.out_dir / "drive_result") : r.status();
        if (r.ok() && drive_result.ok()) {
          std::printf("[%s] drive result: %zu submaps, %zu factors in %s\n", name.c_str(),
                      r->submaps.size(), r->factors.size(),
                      (args.out_dir / "drive_result").string().c_str());
        }
      };
    }
    ModeRun run = RunMode(mode, options, reader, args.pos, tty, &g_stop, on_submap, on_finished);
    if (!drive_result.ok()) warn("drive result not written: " + drive_result.ToString());
    // The map entropy (CPU) beside the writing of the files (mostly one thread formatting and
    // writing): both only read the run.
    std::optional<StatusOr<eval::MapEntropyResult>> entropy;
    std::thread entropy_thread;
    if (!run.map.empty()) {
      entropy_thread = std::thread([&] { entropy = MapEntropyOf(run.map, options.num_threads); });
    }
    Status written = WriteMethodFiles(run, args.out_dir);
    if (run.origin && !geo->run_origin) {
      // georef.json: the world frame of the first method that has an origin.
      geo->run_origin = run.origin;
      const Status g = WriteRunGeoref(*run.origin, *geo, args.out_dir);
      if (written.ok() && !g.ok()) written = g;
    }
    const Status geo_written = WriteGeoOutputs(run, *geo, args.out_dir, run.map_stamps);
    if (written.ok() && !geo_written.ok()) written = geo_written;
    if (entropy_thread.joinable()) entropy_thread.join();
    run.map_entropy = std::move(entropy);
    if (!run.status.ok()) *fatal = run.status;
    if (fatal->ok() && !written.ok()) *fatal = written;
    if (run.complete && written.ok()) {
      // WriteMethodFiles wrote the map as map_<name>.ply (not for lidar_only): the same file.
      const fs::path map_ply = args.out_dir / ("map_" + name + ".ply");
      const bool map_written = mode != MappingMode::kLidarOnly && !run.map.empty();
      const Status c = checkpoint->SaveFinished(run, map_written ? map_ply : fs::path());
      if (!c.ok()) warn("checkpoint: " + c.message() + " (--resume would run " + name + " again)");
    }
    runs->push_back(std::move(run));
    if (!fatal->ok()) break;  // stop the run; evaluate and report what exists
  }
  return OkStatus();
}

}  // namespace

// The options of the run: the app's defaults, the preset, the config file and the output options,
// all checked before any work. Returns the exit code where the run ends here (--config-keys,
// --dump-config, an error).
std::optional<int> PrepareOptions(const RunArgs& args, RunConfig* config, std::string* options_json,
                                  GeoOutputOptions* geo) {
  // The app's defaults: finished submaps' clouds go to a private folder inside --out (removed at
  // the end, also after a signal), so memory stays flat on long drives. In a config file
  // `localizer.spill_dir: "<out>"` (what --dump-config writes) means that folder, `~` keeps them
  // in memory, any other path is used as given.
  MappingSystem::Options& options = config->system;
  options.localizer.spill_dir = kSpillToOutDir;
  if (args.list_config_keys) {
    std::fputs(OptionsToYaml(*config).c_str(), stdout);
    return 0;
  }
  if (args.preset) ApplyLidarPreset(*args.preset, &options);
  if (!args.config.empty()) {
    const Status s = ApplyConfigFile(args.config, config);
    if (!s.ok()) return Fail(s, kExitUsage);
  }
  // --imu-noise asks for the IMU to be modelled with it (and so with the input's own otherwise).
  if (!args.imu_noise.empty()) options.use_stated_imu_noise = true;
  if (!args.dump_config.empty()) {
    const Status s = WriteConfigFile(*config, args.dump_config);
    if (!s.ok()) return Fail(s, kExitUsage);
    std::printf("options written to %s (--config reads it back)\n", args.dump_config.c_str());
    return 0;
  }
  *options_json = OptionsToJson(*config);
  if (options.localizer.spill_dir == kSpillToOutDir) options.localizer.spill_dir = args.out_dir;
  geo->crs = args.crs;
  geo->las_tile_size_m = args.las_tile_size_m;
  const Status s = CheckGeoOutputOptions(*geo);
  if (!s.ok()) return Fail(s, kExitUsage);
  const Status writable = CheckOutputDir(args.out_dir);
  if (!writable.ok()) return Fail(writable, kExitUsage);
  return std::nullopt;
}

// The drive folder: the input's, or the simulated default drive in DIR/sim (a killed run's with
// --resume). Returns the exit code where the run ends here (a failed or stopped simulation).
std::optional<int> ObtainDrive(const RunArgs& args, bool tty,
                               const std::function<void()>& remove_sim, fs::path* drive_dir) {
  *drive_dir = InputPath(args);
  if (!drive_dir->empty()) return std::nullopt;
  const fs::path sim_dir = args.out_dir / "sim";
  if (args.resume) {
    // A killed run leaves its simulated drive; scenario.json is the simulator's last file.
    *drive_dir = CompleteSimulatedDrive(sim_dir);
    if (!drive_dir->empty()) {
      std::printf("[sim] --resume: the simulated drive in %s\n", drive_dir->c_str());
      return std::nullopt;
    }
  }
  bool sim_stopped = false;
  StatusOr<fs::path> simulated = SimulateDefaultDrive(args, tty, &sim_stopped);
  if (!simulated.ok()) return Fail(simulated.status(), kExitError);
  if (sim_stopped) {
    ProgressReporter::BreakLine();
    std::fprintf(stderr, "slam_mms_run: %s during the simulation: nothing processed\n",
                 StopSignalName());
    remove_sim();
    return StopExitCode();
  }
  *drive_dir = *simulated;
  return std::nullopt;
}

// The input opened, the options taken from it (extrinsic, antenna, outages) and checked, and the
// boresight self-calibrated first where asked: every method then runs with the estimate (the
// antenna and everything else as the input gives them). Returns the exit code where the run ends.
std::optional<int> OpenInput(const RunArgs& args, const fs::path& drive_dir, RunConfig* config,
                             std::unique_ptr<DriveReader>* input, std::string* extrinsics_json,
                             std::string* imu_noise) {
  StatusOr<std::unique_ptr<DriveReader>> opened = OpenRunInput(args, drive_dir);
  if (!opened.ok()) return Fail(opened.status(), kExitError);
  *input = std::move(opened).value();
  if ((*input)->NumScans() == 0) {
    return Fail(OutOfRangeError((*input)->Describe() + ": no scan in the frame range"), kExitError);
  }
  MappingSystem::Options& options = config->system;
  options.T_body_lidar = (*input)->streams().T_body_lidar;
  if ((*input)->streams().t_body_antenna_m) {
    options.ins.gnss.t_body_antenna = *(*input)->streams().t_body_antenna_m;
  }
  options.gnss_outages = args.gnss_outages;
  // The IMU's noise: --imu-noise (the reader's, OpenDrive), else the input's imu_noise.yaml;
  // RunDrive applies it. Else the filter's defaults.
  const DriveStreams& streams = (*input)->streams();
  if (UsesStatedImuNoise(options, streams)) *imu_noise = streams.imu_noise_source;
  const Status valid = options.Validate();
  if (!valid.ok()) return Fail(valid, kExitUsage);
  if (!args.calibrate_extrinsics && !config->drive.estimate_extrinsics) return std::nullopt;
  // The clock offset the reader already applies (an --extrinsics file's): its scans' shift.
  const double input_offset_s =
      (*input)->ScanStart(0).SecondsSince((*input)->Underlying().ScanStart(0));
  StatusOr<RunCalibration> calibration = CalibrateRunExtrinsics(
      **input, options, config->drive.extrinsic_calibration, args.out_dir, input_offset_s, &g_stop);
  if (!calibration.ok()) {
    return Fail(calibration.status().WithContext("--calibrate-extrinsics"),
                g_stop.load() ? StopExitCode() : kExitError);
  }
  *input = OverrideExtrinsics(std::move(*input), calibration->extrinsics);
  options.T_body_lidar = (*input)->streams().T_body_lidar;
  *extrinsics_json = std::move(calibration->json);
  return std::nullopt;
}

int RunMain(int argc, const char* const* argv) {
  const LogSinkGuard log_sink;
  SetMinLogLevel(LogLevel::kWarning);
  StatusOr<RunArgs> parsed = ParseRunArgs(argc, argv);
  if (!parsed.ok()) return Fail(parsed.status(), kExitUsage);
  const RunArgs& args = *parsed;
  SetMinLogLevel(args.log_level);
  if (args.help) {
    std::fputs(RunUsage().c_str(), stdout);
    return 0;
  }
  if (args.version) {
    std::printf("%s\n", RunVersion().c_str());
    return 0;
  }
  RunConfig config;
  std::string options_json;
  GeoOutputOptions geo;
  if (std::optional<int> exit = PrepareOptions(args, &config, &options_json, &geo)) return *exit;
  const bool tty = StdoutIsTerminal();
  const StopHandlers stop_handlers;
  std::vector<std::string> warnings;  // also in report.json and report.html
  auto warn = [&warnings](const std::string& text) {
    ProgressReporter::BreakLine();
    std::fprintf(stderr, "slam_mms_run: warning: %s\n", text.c_str());
    warnings.push_back(text);
  };

  // The drive; a simulated one (~2 MB a scan) is removed at the end unless --keep-sim.
  const bool simulated_input = InputPath(args).empty();
  auto remove_sim = [&]() {
    if (!simulated_input || args.keep_sim) return;
    const fs::path sim_dir = args.out_dir / "sim";
    const auto [bytes, files] = DiskUse(sim_dir);
    std::error_code ec;
    fs::remove_all(sim_dir, ec);
    if (ec) {
      warn("cannot remove the simulated drive " + sim_dir.string() + ": " + ec.message());
    } else {
      std::printf("[sim] removed the simulated drive (%zu files, %.0f MB; --keep-sim keeps it)\n",
                  files, static_cast<double>(bytes) / 1e6);
    }
  };
  fs::path drive_dir;
  if (std::optional<int> exit = ObtainDrive(args, tty, remove_sim, &drive_dir)) return *exit;
  std::unique_ptr<DriveReader> input;
  std::string extrinsics_json, imu_noise;
  if (std::optional<int> exit =
          OpenInput(args, drive_dir, &config, &input, &extrinsics_json, &imu_noise)) {
    return *exit;
  }
  std::printf("IMU noise: %s\n", imu_noise.empty() ? "the filter's defaults (the input states none)"
                                                   : imu_noise.c_str());
  const DriveReader& reader = *input;
  const MappingSystem::Options& options = config.system;

  // The checkpoint (checkpoint.hpp): a fresh one, or the killed run's with --resume.
  const RunFingerprint fingerprint =
      MakeFingerprint(args, simulated_input ? fs::path() : drive_dir, options_json);
  StatusOr<Checkpoint> checkpoint = args.resume ? Checkpoint::Resume(args.out_dir, fingerprint)
                                                : Checkpoint::Start(args.out_dir, fingerprint);
  if (!checkpoint.ok()) {
    return Fail(checkpoint.status(), args.resume ? kExitUsage : kExitError);
  }

  // Ground truth: <gt_dir>/ground_truth/ (simulated drives, also converted to a folder or bag),
  // else the OXTS poses of a KITTI raw drive.
  const fs::path gt_dir = GroundTruthDir(args, drive_dir);
  const bool sim_gt = eval::HasSimulatorGroundTruth(gt_dir);
  const bool kitti_input = dynamic_cast<const KittiDriveReader*>(&reader.Underlying()) != nullptr;
  const std::string gt_kind = sim_gt ? "simulator" : kitti_input ? "oxts" : "none";
  const Timestamp first_scan = reader.ScanStart(0);
  const double duration_s = reader.ScanEnd(reader.NumScans() - 1).SecondsSince(first_scan);
  AnnounceInput(reader, args, gt_kind, duration_s, warn);
  std::fflush(stdout);

  // The methods, each with its own MappingSystem; files written as soon as a method ends.
  std::vector<ModeRun> runs;
  Status fatal;
  {
    const Status s =
        RunMethods(args, options, reader, tty, &*checkpoint, &geo, warn, &runs, &fatal);
    if (!s.ok()) return Fail(s, kExitError);
  }
  const bool stopped = g_stop.load();
  if (stopped) {
    warn(std::string(StopSignalName()) + ": the run was stopped after " +
         std::to_string(runs.empty() ? 0 : runs.back().scans_processed) + " of " +
         std::to_string(reader.NumScans()) + " scans of " +
         (runs.empty() ? std::string("the first method") : runs.back().name) +
         "; the outputs hold what was computed so far (report.json \"complete\": false)");
  }

  ReportInput rin{args,         reader,          drive_dir,  simulated_input,
                  gt_dir,       gt_kind,         first_scan, duration_s,
                  options_json, extrinsics_json, geo,        options.num_threads,
                  stopped,      warnings,        imu_noise};
  EvaluateAndReport(rin, &runs, &*checkpoint, remove_sim, &fatal);
  const auto [out_bytes, out_files] = DiskUse(args.out_dir);
  std::printf("outputs in %s (%zu files, %.0f MB)\n", args.out_dir.c_str(), out_files,
              static_cast<double>(out_bytes) / 1e6);
  std::fflush(stdout);
  if (!fatal.ok()) return Fail(fatal, kExitError);
  if (stopped) return StopExitCode();
  return 0;
}

}  // namespace slam_mms::app
