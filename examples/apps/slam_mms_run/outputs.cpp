#include "slam_mms_run/outputs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/drive/scan_results_csv.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/eval/relative_error.hpp"
#include "slam_mms/io/map_io.hpp"
#include "slam_mms/io/trajectory_io.hpp"

namespace slam_mms::app {
namespace {

void KeepFirst(Status* first, const Status& s) {
  if (!s.ok()) {
    SLAM_MMS_LOG(kError) << s.ToString();
    if (first->ok()) *first = s;
  }
}

std::string Cell(const std::optional<double>& v, const char* format) {
  if (!v || !std::isfinite(*v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, *v);
  return buf;
}

// The stamps of a .kitti file (KITTI odometry's times.txt: one time a line, here UTC seconds with
// nanosecond digits), which the format itself does not hold.
Status WriteKittiTimes(const Trajectory& trajectory, const std::filesystem::path& file) {
  std::ofstream f(file);
  for (const StampedPose& p : trajectory.poses()) f << FormatSecondsExact(p.stamp) << '\n';
  f.flush();
  if (!f) return UnavailableError("cannot write " + file.string());
  return OkStatus();
}

}  // namespace

Status WriteMethodFiles(const ModeRun& run, const std::filesystem::path& out_dir) {
  Status first;
  if (!run.trajectory.empty()) {
    KeepFirst(&first, WriteTrajectoryTum(run.trajectory, out_dir / (run.name + ".tum")));
    KeepFirst(&first, WriteTrajectoryKitti(run.trajectory, out_dir / (run.name + ".kitti")));
    KeepFirst(&first, WriteKittiTimes(run.trajectory, out_dir / (run.name + "_times.txt")));
    KeepFirst(&first, WriteTrajectoryCsv(run.trajectory, out_dir / (run.name + "_cov.csv")));
  } else {
    SLAM_MMS_LOG(kWarning) << run.name << ": no pose estimated, no trajectory written";
  }
  if (!run.results.empty())
    KeepFirst(&first, WriteScanResultsCsv(run.results, out_dir / (run.name + "_scans.csv")));
  const bool pos_only =
      run.mode == MappingMode::kGnssIns || run.mode == MappingMode::kGnssInsSmoothed;
  if (!pos_only && !run.results.empty()) {
    // Level 1 alone (before any level-2 correction): the "before" of the paper's Table 2.
    Trajectory level1;
    for (const LocalizationResult& r : run.results) {
      if (!level1.Add(r.stamp, r.T_world_body).ok()) break;
    }
    KeepFirst(&first, WriteTrajectoryTum(level1, out_dir / (run.name + "_level1.tum")));
  }
  const bool map_wanted = run.mode != MappingMode::kLidarOnly;
  if (map_wanted && !run.map.empty()) {
    MapCloud map;
    map.cloud = run.map;
    const std::string base = "map_" + run.name;
    KeepFirst(&first, WritePly(map, out_dir / (base + ".ply")));
    KeepFirst(&first, WritePcd(map, out_dir / (base + ".pcd")));
    // map_<name>.las (or its tiles): WriteGeoOutputs (geo_outputs.hpp).
  } else if (map_wanted) {
    SLAM_MMS_LOG(kWarning) << run.name << ": empty map, map files not written";
  }
  return first;
}

StatusOr<eval::MapEntropyResult> MapEntropyOf(const PointCloud& map, int num_threads) {
  eval::MapEntropyOptions mo;
  mo.num_threads = num_threads;
  return eval::ComputeMapEntropy(map, mo);
}

namespace {

// ATE, outage errors and relative errors of the run's trajectory against `gt` (warnings name the
// method and `what` reference).
struct TrajectoryMetrics {
  std::optional<eval::AteResult> ate;
  std::optional<eval::RelativeErrorResult> relative;
  std::optional<eval::OutageErrorResult> outage;
  std::string relative_label;
  size_t relative_segments = 0;
  size_t outage_poses = 0;
};

TrajectoryMetrics MeasureTrajectory(const ModeRun& run, const Trajectory& gt,
                                    const std::vector<eval::OutageWindow>& outages,
                                    Timestamp reference, const char* what) {
  TrajectoryMetrics t;
  if (run.trajectory.empty()) return t;
  StatusOr<eval::AteResult> ate = eval::ComputeAte(run.trajectory, gt);
  if (ate.ok()) {
    t.ate = *ate;
    StatusOr<eval::OutageErrorResult> o =
        eval::ComputeOutageErrors(ate->errors, outages, reference);
    if (o.ok()) {
      t.outage = *o;
      t.outage_poses = o->num_poses;
    } else {
      SLAM_MMS_LOG(kWarning) << run.name << ": outage errors" << what << ": "
                             << o.status().ToString();
    }
  } else {
    SLAM_MMS_LOG(kWarning) << run.name << ": ATE" << what << ": " << ate.status().ToString();
  }
  if (run.trajectory.size() < 2) return t;
  // The devkit's 100..800 m where the drive is long enough, else 10..80 m (named so).
  StatusOr<eval::MatchedPoses> matched = eval::MatchByTimestamp(run.trajectory, gt);
  double path_m = 0.0;
  if (matched.ok()) {
    for (size_t i = 1; i < matched->size(); ++i) {
      path_m +=
          (matched->T_world_gt[i].translation() - matched->T_world_gt[i - 1].translation()).norm();
    }
  }
  const eval::RelativeErrorOptions rel_options = path_m >= 400.0
                                                     ? eval::RelativeErrorOptions::Kitti()
                                                     : eval::RelativeErrorOptions::ShortDrive();
  t.relative_label = rel_options.LengthsLabel();
  StatusOr<eval::RelativeErrorResult> r =
      eval::ComputeRelativeError(run.trajectory, gt, rel_options);
  if (r.ok()) {
    t.relative = *r;
    t.relative_segments = r->num_segments;
  } else {
    SLAM_MMS_LOG(kWarning) << run.name << ": relative error" << what << ": "
                           << r.status().ToString();
  }
  return t;
}

}  // namespace

eval::ReferenceMetrics EvaluateAgainst(const ModeRun& run, const Trajectory& T_world_reference,
                                       const std::vector<eval::OutageWindow>& outages,
                                       Timestamp reference) {
  const TrajectoryMetrics t =
      MeasureTrajectory(run, T_world_reference, outages, reference, " (second reference)");
  return eval::MakeReferenceMetrics(t.ate ? &*t.ate : nullptr, t.relative ? &*t.relative : nullptr,
                                    t.outage ? &*t.outage : nullptr);
}

MethodEvaluation EvaluateMethod(const ModeRun& run, const eval::GroundTruth* gt,
                                const std::vector<eval::OutageWindow>& outages, Timestamp reference,
                                int num_threads) {
  MethodEvaluation ev;
  ev.name = run.name;
  std::optional<eval::RelativeErrorResult> relative;
  std::optional<eval::OutageErrorResult> outage;
  std::optional<eval::MapEntropyResult> entropy;
  std::optional<eval::NeesResult> nees;
  if (gt != nullptr && !run.trajectory.empty() &&
      (run.mode == MappingMode::kGnssIns || run.mode == MappingMode::kGnssInsSmoothed)) {
    // The POS's covariances are absolute (level 1's are relative to their submap).
    StatusOr<eval::NeesResult> n = eval::ComputeNees(run.trajectory, gt->T_world_body);
    if (n.ok()) {
      nees = *n;
    } else {
      SLAM_MMS_LOG(kWarning) << run.name << ": NEES: " << n.status().ToString();
    }
  }
  if (gt != nullptr) {
    TrajectoryMetrics t = MeasureTrajectory(run, gt->T_world_body, outages, reference, "");
    ev.ate = std::move(t.ate);
    relative = std::move(t.relative);
    outage = std::move(t.outage);
    ev.relative_label = t.relative_label;
    ev.relative_segments = t.relative_segments;
    ev.outage_poses = t.outage_poses;
  }
  if (!run.map.empty()) {
    const StatusOr<eval::MapEntropyResult> e =
        run.map_entropy ? *run.map_entropy : MapEntropyOf(run.map, num_threads);
    if (e.ok()) {
      entropy = *e;
      ev.mme_points = e->num_valid_points;
    } else {
      SLAM_MMS_LOG(kWarning) << run.name << ": map entropy: " << e.status().ToString();
    }
  }
  ev.report = eval::MakeMethodReport(ev.ate ? &*ev.ate : nullptr, relative ? &*relative : nullptr,
                                     outage ? &*outage : nullptr, entropy ? &*entropy : nullptr,
                                     nees ? &*nees : nullptr);
  ev.report.scans_per_s = run.scans_per_s;
  ev.report.peak_rss_mb = run.peak_rss_mb;
  return ev;
}

std::string SummaryTable(const std::vector<MethodEvaluation>& evals,
                         const std::optional<double>& gt_map_mme, const std::string& gt_kind) {
  std::ostringstream s;
  char line[512];
  std::snprintf(line, sizeof(line), "%-17s %9s %9s %9s %12s %14s %8s %8s %9s\n", "method", "ATE[m]",
                "rotRMSE", "t_rel[%]", "r_rel[d/100]", "maxErrOut[m]", "MME", "scans/s", "RSS[MB]");
  s << line;
  for (const MethodEvaluation& e : evals) {
    const eval::MethodReport& m = e.report;
    std::snprintf(line, sizeof(line), "%-17s %9s %9s %9s %12s %14s %8s %8s %9s\n", e.name.c_str(),
                  Cell(m.ate_rmse_m, "%.3f").c_str(), Cell(m.rot_rmse_deg, "%.3f").c_str(),
                  Cell(m.t_rel_pct, "%.3f").c_str(), Cell(m.r_rel_deg_per_100m, "%.4f").c_str(),
                  Cell(m.max_pos_err_in_outage_m, "%.3f").c_str(), Cell(m.mme, "%.4f").c_str(),
                  Cell(m.scans_per_s, "%.2f").c_str(), Cell(m.peak_rss_mb, "%.0f").c_str());
    s << line;
  }
  const bool second = std::any_of(evals.begin(), evals.end(), [](const MethodEvaluation& e) {
    return e.report.vs_oxts_velocity.has_value();
  });
  if (second) {
    s << "against the OXTS velocities integrated from its first record (sharper over seconds, "
         "not absolute; ground_truth_oxts_velocity.tum):\n";
    for (const MethodEvaluation& e : evals) {
      if (!e.report.vs_oxts_velocity) continue;
      const eval::ReferenceMetrics& r = *e.report.vs_oxts_velocity;
      std::snprintf(line, sizeof(line), "%-17s %9s %9s %9s %12s %14s\n", e.name.c_str(),
                    Cell(r.ate_rmse_m, "%.3f").c_str(), Cell(r.rot_rmse_deg, "%.3f").c_str(),
                    Cell(r.t_rel_pct, "%.3f").c_str(), Cell(r.r_rel_deg_per_100m, "%.4f").c_str(),
                    Cell(r.max_pos_err_in_outage_m, "%.3f").c_str());
      s << line;
    }
  }
  s << "ground-truth map MME: " << Cell(gt_map_mme, "%.4f") << "\n";
  s << "ATE and rotation RMSE without alignment, against the " << gt_kind
    << " ground truth interpolated at each scan's start; rotRMSE in deg.\n";
  for (const MethodEvaluation& e : evals) {
    if (!e.relative_label.empty()) {
      s << e.name << ": t_rel/r_rel over segments " << e.relative_label << " ("
        << e.relative_segments << " segments); " << e.outage_poses
        << " poses inside GNSS outages; MME over " << e.mme_points << " points\n";
    }
  }
  return s.str();
}

}  // namespace slam_mms::app
