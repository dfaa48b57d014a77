// slam_mms_run: the main job (issue 8). A KITTI raw drive (or the embedded default drive, simulated
// first) in; per method (full, gnss_ins, gnss_ins_smoothed, lidar_only) trajectories and maps out,
// evaluated against the ground truth (simulator's, else OXTS) in report.json, plots and a summary
// table.
//
//   slam_mms_run --kitti-raw DRIVE_DIR --out DIR [--mode full|gnss_ins|gnss_ins_smoothed|
//                lidar_only|all] [--pos forward|smoothed] [--frames A:B]
//                [--gnss-outage START_S:DURATION_S ...] [--config FILE]
//   slam_mms_run --out DIR
//
// Errors: a scan that cannot be read is skipped with a warning naming its file; any other input or
// processing error stops the run with a message naming file/line/field, after everything computed
// so far is written (trajectories, maps, report with what exists); exit status 1. A bad command
// line or config file: exit status 2.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/eval/ground_truth.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/eval/report.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/io/map_io.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms_run/cli.hpp"
#include "slam_mms_run/config_file.hpp"
#include "slam_mms_run/input.hpp"
#include "slam_mms_run/outputs.hpp"
#include "slam_mms_run/progress.hpp"
#include "slam_mms_run/run_mode.hpp"

namespace fs = std::filesystem;
using namespace slam_mms;       // NOLINT(google-build-using-namespace)
using namespace slam_mms::app;  // NOLINT(google-build-using-namespace)

namespace {

constexpr int kExitError = 1;
constexpr int kExitUsage = 2;

int Fail(const Status& status, int code) {
  ProgressReporter::BreakLine();
  std::fprintf(stderr, "slam_mms_run: error: %s\n", status.message().c_str());
  return code;
}

// Simulates the embedded default drive into out/sim; returns the drive folder.
StatusOr<fs::path> SimulateDefaultDrive(const RunArgs& args, bool tty) {
  sim::DriveSimulator::Options so;
  so.scenario = "default";
  so.duration_s = args.sim_duration_s;
  so.seed = args.sim_seed;
  std::printf("[sim] simulating the default drive (%s, seed %llu) into %s\n",
              args.sim_duration_s > 0 ? (std::to_string(args.sim_duration_s) + " s").c_str()
                                      : "whole route",
              static_cast<unsigned long long>(args.sim_seed), (args.out_dir / "sim").c_str());
  std::fflush(stdout);
  SLAM_MMS_ASSIGN_OR_RETURN(sim::DriveSimulator simulator, sim::DriveSimulator::Create(so));
  ProgressReporter progress("sim", static_cast<size_t>(simulator.num_scans()), tty);
  SLAM_MMS_ASSIGN_OR_RETURN(
      const sim::DriveSimulator::Summary summary,
      simulator.Run(args.out_dir / "sim", [&](int done, int) { progress.Update(done); }));
  char note[160];
  std::snprintf(note, sizeof(note), "(%.0f m, %.1f s simulated)", summary.path_length_m,
                summary.simulated_seconds);
  progress.Finish(static_cast<size_t>(summary.num_scans), note);
  return summary.drive_dir;
}

bool SameOrigin(const GeodeticPoint& a, const GeodeticPoint& b) {
  return a.latitude_deg == b.latitude_deg && a.longitude_deg == b.longitude_deg &&
         a.height_m == b.height_m;
}

}  // namespace

int main(int argc, char** argv) {
  InstallLogSink();
  SetMinLogLevel(LogLevel::kWarning);
  StatusOr<RunArgs> parsed = ParseRunArgs(argc, argv);
  if (!parsed.ok()) return Fail(parsed.status(), kExitUsage);
  const RunArgs& args = *parsed;
  SetMinLogLevel(args.log_level);
  if (args.help) {
    std::fputs(RunUsage().c_str(), stdout);
    return 0;
  }
  if (args.list_config_keys) {
    std::printf("| key | type | default |\n|---|---|---|\n");
    for (const ConfigKeyInfo& k : ConfigKeys()) {
      std::printf("| `%s` | %s | %s |\n", k.key.c_str(), k.type.c_str(), k.default_value.c_str());
    }
    return 0;
  }
  const bool tty = StdoutIsTerminal();

  // Options: defaults, then the config file (checked before any work).
  MappingSystem::Options options;
  // Finished submaps' clouds go to a private folder inside --out (removed at the end), so memory
  // stays flat on long drives; `localizer.spill_dir = none` in the config keeps them in memory.
  options.localizer.spill_dir = args.out_dir;
  if (!args.config.empty()) {
    const Status s = ApplyConfigFile(args.config, &options);
    if (!s.ok()) return Fail(s, kExitUsage);
  }
  std::error_code ec;
  fs::create_directories(args.out_dir, ec);
  if (ec) {
    return Fail(InvalidArgumentError("--out " + args.out_dir.string() + ": " + ec.message()),
                kExitUsage);
  }

  // The drive.
  fs::path drive_dir = InputPath(args);
  if (drive_dir.empty()) {
    StatusOr<fs::path> simulated = SimulateDefaultDrive(args, tty);
    if (!simulated.ok()) return Fail(simulated.status(), kExitError);
    drive_dir = *simulated;
  }
  StatusOr<std::unique_ptr<DriveReader>> opened = OpenRunInput(args, drive_dir);
  if (!opened.ok()) return Fail(opened.status(), kExitError);
  const DriveReader& reader = **opened;
  if (reader.NumScans() == 0) {
    return Fail(OutOfRangeError(reader.Describe() + ": no scan in the frame range"), kExitError);
  }
  options.T_body_lidar = reader.streams().T_body_lidar;
  if (reader.streams().t_body_antenna_m) {
    options.ins.gnss.t_body_antenna = *reader.streams().t_body_antenna_m;
  }
  options.gnss_outages = args.gnss_outages;
  const Status valid = options.Validate();
  if (!valid.ok()) return Fail(valid, kExitUsage);

  // Ground truth: <gt_dir>/ground_truth/ (simulated drives, also converted to a folder or bag),
  // else the OXTS poses of a KITTI raw drive.
  const fs::path gt_dir = GroundTruthDir(args, drive_dir);
  const bool sim_gt = eval::HasSimulatorGroundTruth(gt_dir);
  const bool kitti_input = dynamic_cast<const KittiDriveReader*>(&reader) != nullptr;
  const std::string gt_kind = sim_gt ? "simulator" : kitti_input ? "oxts" : "none";
  const Timestamp first_scan = reader.ScanStart(0);
  const double duration_s = reader.ScanEnd(reader.NumScans() - 1).SecondsSince(first_scan);
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
  }
  std::fflush(stdout);

  // The methods, each with its own MappingSystem; files written as soon as a method ends.
  std::vector<ModeRun> runs;
  Status fatal;
  for (const MappingMode mode : args.modes) {
    ModeRun run = RunMode(mode, options, reader, args.pos, tty);
    const Status written = WriteMethodFiles(run, args.out_dir);
    if (!run.status.ok()) fatal = run.status;
    if (fatal.ok() && !written.ok()) fatal = written;
    runs.push_back(std::move(run));
    if (!fatal.ok()) break;  // stop the run; evaluate and report what exists
  }

  // Ground truth in each run's world frame (one load per distinct origin).
  std::optional<GeodeticPoint> any_origin;
  for (const ModeRun& r : runs) {
    if (r.origin && !any_origin) any_origin = r.origin;
  }
  std::vector<std::pair<GeodeticPoint, eval::GroundTruth>> gts;
  std::vector<const eval::GroundTruth*> gt_of_run(runs.size(), nullptr);
  for (size_t i = 0; i < runs.size(); ++i) {
    std::optional<GeodeticPoint> origin = runs[i].origin ? runs[i].origin : any_origin;
    if (!origin) {
      SLAM_MMS_LOG(kWarning) << runs[i].name << ": world origin unknown, no metrics";
      continue;
    }
    bool found = false;
    for (const auto& [o, gt] : gts) found = found || SameOrigin(o, *origin);
    if (!found) {
      StatusOr<eval::GroundTruth> gt = eval::LoadGroundTruth(gt_dir, reader, *origin);
      if (!gt.ok()) {
        if (gt.status().code() == StatusCode::kNotFound && gt_kind == "none") break;
        SLAM_MMS_LOG(kError) << "ground truth: " << gt.status().ToString();
        if (fatal.ok()) fatal = gt.status();
        continue;
      }
      gts.emplace_back(*origin, std::move(gt).value());
      // The ground truth in the run's world frame, so that slam_mms_eval can compare any output
      // (e.g. <method>_level1.tum) with it.
      const std::string name = gts.size() == 1
                                   ? "ground_truth.tum"
                                   : "ground_truth_" + std::to_string(gts.size()) + ".tum";
      const Status written =
          WriteTrajectoryTum(gts.back().second.T_world_body, args.out_dir / name);
      if (!written.ok()) {
        SLAM_MMS_LOG(kWarning) << written.ToString();
      }
    }
  }
  for (size_t i = 0; i < runs.size(); ++i) {
    const std::optional<GeodeticPoint> origin = runs[i].origin ? runs[i].origin : any_origin;
    for (const auto& [o, gt] : gts) {
      if (origin && SameOrigin(o, *origin)) gt_of_run[i] = &gt;
    }
  }

  // Outage windows are relative to the first scan the systems were given (scan 0 unless it was
  // unreadable).
  Timestamp reference = first_scan;
  for (const ModeRun& r : runs) {
    if (r.first_scan_start) {
      reference = *r.first_scan_start;
      break;
    }
  }
  std::printf("[eval] metrics and map entropy ...\n");
  std::fflush(stdout);
  std::vector<eval::OutageWindow> windows;
  for (const auto& [start, duration] : args.gnss_outages) windows.push_back({start, duration});
  std::vector<MethodEvaluation> evals;
  for (size_t i = 0; i < runs.size(); ++i) {
    evals.push_back(EvaluateMethod(runs[i], gt_of_run[i], windows, reference, options.num_threads));
  }
  std::optional<double> gt_map_mme;
  if (!gts.empty() && !gts.front().second.scene_map.empty()) {
    StatusOr<MapCloud> scene = ReadPly(gts.front().second.scene_map);
    if (scene.ok()) {
      eval::MapEntropyOptions mo;
      mo.num_threads = options.num_threads;
      StatusOr<eval::MapEntropyResult> e = eval::ComputeMapEntropy(scene->cloud, mo);
      if (e.ok() && std::isfinite(e->mean_map_entropy)) gt_map_mme = e->mean_map_entropy;
    } else {
      SLAM_MMS_LOG(kWarning) << "ground-truth map: " << scene.status().ToString();
    }
  }

  // report.json (exact schema), plots, summary.
  eval::EvalReport report;
  report.input.drive = drive_dir.string();
  for (const ModeRun& r : runs) {
    report.input.scans =
        std::max<int64_t>(report.input.scans, static_cast<int64_t>(r.scans_processed));
  }
  report.input.duration_s = duration_s;
  report.input.ground_truth = gts.empty() ? gt_kind : gts.front().second.kind;
  report.gnss_outages = windows;
  for (const MethodEvaluation& e : evals) report.methods.emplace_back(e.name, e.report);
  report.ground_truth_map_mme = gt_map_mme;
  const Status report_written = eval::WriteReportJson(report, args.out_dir / "report.json");
  if (!report_written.ok()) {
    SLAM_MMS_LOG(kError) << report_written.ToString();
    if (fatal.ok()) fatal = report_written;
  }
  WritePlots(runs, evals, gts.empty() ? nullptr : &gts.front().second, windows, reference,
             args.out_dir);
  const std::string table = SummaryTable(evals, gt_map_mme, report.input.ground_truth);
  std::ofstream(args.out_dir / "summary.txt") << table;
  ProgressReporter::BreakLine();
  std::printf("\n%s", table.c_str());
  std::printf("outputs in %s\n", args.out_dir.c_str());
  std::fflush(stdout);
  if (!fatal.ok()) return Fail(fatal, kExitError);
  return 0;
}
