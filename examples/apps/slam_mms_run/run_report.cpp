#include "slam_mms_run/run_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/eval/ground_truth.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/eval/report.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/io/map_io.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms_run/outputs.hpp"
#include "slam_mms_run/plot_outputs.hpp"
#include "slam_mms_run/progress.hpp"

namespace slam_mms::app {

namespace fs = std::filesystem;

namespace {

// Calls fn(path, size) for every regular file under `dir` (unreadable entries are passed over).
template <typename Fn>
void ForEachFile(const fs::path& dir, Fn fn) {
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code e2;
    if (!it->is_regular_file(e2)) continue;
    const uintmax_t n = it->file_size(e2);
    fn(it->path(), e2 ? uintmax_t{0} : n);
  }
}

}  // namespace

std::pair<uintmax_t, size_t> DiskUse(const fs::path& dir) {
  uintmax_t bytes = 0;
  size_t files = 0;
  ForEachFile(dir, [&](const fs::path&, uintmax_t n) {
    bytes += n;
    ++files;
  });
  return {bytes, files};
}

// Regular files under `dir`, relative to it (report.json's "outputs").
std::vector<std::string> OutputFiles(const fs::path& dir) {
  std::vector<std::string> files;
  ForEachFile(dir, [&](const fs::path& file, uintmax_t) {
    std::error_code ec;
    files.push_back(fs::relative(file, dir, ec).string());
  });
  std::sort(files.begin(), files.end());
  return files;
}

namespace {

// DriveRun::skipped_scans entries are "<source>: <reason>".
eval::SkippedScan SplitSkippedScan(const std::string& entry) {
  const size_t colon = entry.find(": ");
  if (colon == std::string::npos) return {entry, ""};
  eval::SkippedScan s{entry.substr(0, colon), entry.substr(colon + 2)};
  // Reader messages often start with the file again.
  if (s.reason.rfind(s.source + ": ", 0) == 0) s.reason = s.reason.substr(s.source.size() + 2);
  return s;
}

bool SameOrigin(const GeodeticPoint& a, const GeodeticPoint& b) {
  return a.latitude_deg == b.latitude_deg && a.longitude_deg == b.longitude_deg &&
         a.height_m == b.height_m;
}

}  // namespace

void EvaluateAndReport(const ReportInput& in, std::vector<ModeRun>* runs_out,
                       Checkpoint* checkpoint, const std::function<void()>& before_outputs,
                       Status* fatal) {
  std::vector<ModeRun>& runs = *runs_out;
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
      StatusOr<eval::GroundTruth> gt = eval::LoadGroundTruth(in.gt_dir, in.reader, *origin);
      if (!gt.ok()) {
        if (gt.status().code() == StatusCode::kNotFound && in.gt_kind == "none") break;
        SLAM_MMS_LOG(kError) << "ground truth: " << gt.status().ToString();
        if (fatal->ok()) *fatal = gt.status();
        continue;
      }
      gts.emplace_back(*origin, std::move(gt).value());
      // The ground truth in the run's world frame, so that slam_mms_eval can compare any output
      // (e.g. <method>_level1.tum) with it.
      const std::string name = gts.size() == 1
                                   ? "ground_truth.tum"
                                   : "ground_truth_" + std::to_string(gts.size()) + ".tum";
      const Status written =
          WriteTrajectoryTum(gts.back().second.T_world_body, in.args.out_dir / name);
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
  Timestamp reference = in.first_scan;
  for (const ModeRun& r : runs) {
    if (r.first_scan_start) {
      reference = *r.first_scan_start;
      break;
    }
  }
  std::printf("[eval] metrics and map entropy ...\n");
  std::fflush(stdout);
  std::vector<eval::OutageWindow> windows;
  for (const auto& [start, duration] : in.args.gnss_outages) windows.push_back({start, duration});
  std::vector<MethodEvaluation> evals;
  for (size_t i = 0; i < runs.size(); ++i) {
    evals.push_back(EvaluateMethod(runs[i], gt_of_run[i], windows, reference, in.num_threads));
  }
  // An OXTS's recorded positions follow its GNSS and wander over seconds (on drive 0013 about 1 deg
  // off its own velocities); its velocities integrated are the sharper second reference
  // (eval/oxts_reference.hpp). Each method is measured against both.
  if (gts.size() == 1 && gts.front().second.kind == "oxts") {
    StatusOr<eval::GroundTruth> vel = eval::LoadOxtsGroundTruth(
        in.reader, gts.front().first, eval::OxtsPositions::kVelocityIntegrated);
    if (vel.ok()) {
      const Status written =
          WriteTrajectoryTum(vel->T_world_body, in.args.out_dir / "ground_truth_oxts_velocity.tum");
      if (!written.ok()) {
        SLAM_MMS_LOG(kWarning) << written.ToString();
      }
      for (size_t i = 0; i < runs.size(); ++i) {
        if (gt_of_run[i] == nullptr) continue;
        evals[i].report.vs_oxts_velocity =
            EvaluateAgainst(runs[i], vel->T_world_body, windows, reference);
      }
    } else {
      SLAM_MMS_LOG(kWarning) << "OXTS velocity reference: " << vel.status().ToString();
    }
  }
  std::optional<double> gt_map_mme;
  if (!gts.empty() && !gts.front().second.scene_map.empty()) {
    StatusOr<MapCloud> scene = ReadPly(gts.front().second.scene_map);
    if (scene.ok()) {
      eval::MapEntropyOptions mo;
      mo.num_threads = in.num_threads;
      StatusOr<eval::MapEntropyResult> e = eval::ComputeMapEntropy(scene->cloud, mo);
      if (e.ok() && std::isfinite(e->mean_map_entropy)) gt_map_mme = e->mean_map_entropy;
    } else {
      SLAM_MMS_LOG(kWarning) << "ground-truth map: " << scene.status().ToString();
    }
  }

  // report.json (exact schema), plots, summary.
  eval::EvalReport report;
  report.input.drive = in.drive_dir.string();
  for (const ModeRun& r : runs) {
    report.input.scans =
        std::max<int64_t>(report.input.scans, static_cast<int64_t>(r.scans_processed));
  }
  report.input.duration_s = in.duration_s;
  report.input.ground_truth = gts.empty() ? in.gt_kind : gts.front().second.kind;
  report.input.kind = in.simulated_input        ? "simulated"
                      : !in.args.folder.empty() ? "folder"
                      : !in.args.rosbag.empty() ? "rosbag"
                                                : "kitti_raw";
  report.input.scans_total = static_cast<int64_t>(in.reader.NumScans());
  report.input.imu_noise = in.imu_noise;
  if (const auto* kitti = dynamic_cast<const KittiDriveReader*>(&in.reader.Underlying())) {
    report.input.oxts_inertial_delay_s = kitti->kitti().oxts_inertial_delay_s();
  }
  // The skipped scans are the reader's, the same for every method: the first run's list.
  if (!runs.empty()) {
    for (const std::string& entry : runs.front().skipped_scans) {
      report.input.skipped_scans.push_back(SplitSkippedScan(entry));
    }
  }
  report.command_line = in.args.command_line;
  report.extrinsics_json = in.extrinsics_json;
  report.options_json = in.options_json;
  if (in.geo.run_origin) {
    StatusOr<std::string> georef = RunGeorefJson(*in.geo.run_origin, in.geo);
    if (georef.ok()) {
      report.georef_json = *georef;
    } else {
      SLAM_MMS_LOG(kWarning) << "georef: " << georef.status().ToString();
    }
  }
  report.complete =
      !in.stopped && fatal->ok() && !runs.empty() && runs.size() == in.args.modes.size() &&
      std::all_of(runs.begin(), runs.end(), [](const ModeRun& r) { return r.complete; });
  report.warnings = in.warnings;
  report.gnss_outages = windows;
  for (const MethodEvaluation& e : evals) report.methods.emplace_back(e.name, e.report);
  report.ground_truth_map_mme = gt_map_mme;
  WritePlots(runs, evals, gts.empty() ? nullptr : &gts.front().second, windows, reference,
             in.args.out_dir);
  const std::string table = SummaryTable(evals, gt_map_mme, report.input.ground_truth);
  std::ofstream(in.args.out_dir / "summary.txt") << table;
  ProgressReporter::BreakLine();
  std::printf("\n%s", table.c_str());
  before_outputs();
  // report.json lists every file of the run (itself and report.html included), then report.html
  // is written last: it embeds the plots and describes the files.
  if (report.complete) {
    checkpoint->Remove();  // nothing to resume
  } else {
    std::printf("[checkpoint] %s: `--resume` with the same command line continues this run\n",
                checkpoint->dir().c_str());
  }
  report.outputs = OutputFiles(in.args.out_dir);
  for (const char* name : {"report.json", "report.html"}) {
    if (std::find(report.outputs.begin(), report.outputs.end(), name) == report.outputs.end()) {
      report.outputs.push_back(name);
    }
  }
  std::sort(report.outputs.begin(), report.outputs.end());
  const Status report_written = eval::WriteReportJson(report, in.args.out_dir / "report.json");
  if (!report_written.ok()) {
    SLAM_MMS_LOG(kError) << report_written.ToString();
    if (fatal->ok()) *fatal = report_written;
  }
  const Status html_written = WriteReportHtml(report, runs, evals, in.warnings, in.args.out_dir);
  if (!html_written.ok()) {
    SLAM_MMS_LOG(kError) << html_written.ToString();
    if (fatal->ok()) *fatal = html_written;
  }
}

}  // namespace slam_mms::app
