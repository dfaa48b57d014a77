#include "slam_mms_run/plot_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <system_error>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/eval/html_report.hpp"
#include "slam_mms/eval/plots.hpp"
#include "slam_mms/version.hpp"

namespace slam_mms::app {
namespace {

std::string Format(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

std::string Cell(const std::optional<double>& v, const char* format) {
  return v && std::isfinite(*v) ? Format(format, *v) : "-";
}

bool StartsWith(const std::string& s, const std::string& prefix) {
  return s.size() >= prefix.size() && s.compare(0, prefix.size(), prefix) == 0;
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// georef.json flattened to "a.b" -> value rows; the file lists and very long texts (WKT) left
// to georef.json itself.
void FlattenJson(const nlohmann::ordered_json& j, const std::string& prefix,
                 std::vector<std::pair<std::string, std::string>>* rows) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it.key() == "files" || it.key() == "format" || it.key() == "format_version") continue;
    if (it->is_object()) {
      FlattenJson(*it, key, rows);
      continue;
    }
    std::string value = it->is_string() ? it->get<std::string>() : it->dump();
    if (value.size() > 240) value = value.substr(0, 200) + " ... (in full in georef.json)";
    rows->emplace_back(key, value);
  }
}

}  // namespace

void WritePlots(const std::vector<ModeRun>& runs, const std::vector<MethodEvaluation>& evals,
                const eval::GroundTruth* gt, const std::vector<eval::OutageWindow>& outages,
                Timestamp reference, const std::filesystem::path& out_dir) {
  auto warn = [](const char* what, const Status& s) {
    if (!s.ok()) {
      SLAM_MMS_LOG(kWarning) << what << ": " << s.ToString();
    }
  };
  std::vector<eval::NamedTrajectory> methods;
  for (const ModeRun& r : runs) {
    if (!r.trajectory.empty()) methods.push_back({r.name, r.trajectory});
  }
  if (gt != nullptr && !methods.empty()) {
    // The ground truth over the span of the estimates only (the simulator's covers the lead-in).
    Trajectory gt_span;
    Timestamp t_min = methods.front().trajectory.start(), t_max = methods.front().trajectory.end();
    for (const auto& m : methods) {
      t_min = std::min(t_min, m.trajectory.start());
      t_max = std::max(t_max, m.trajectory.end());
    }
    for (const StampedPose& p : gt->T_world_body.poses()) {
      if (p.stamp >= t_min && p.stamp <= t_max) (void)gt_span.Add(p);
    }
    if (gt_span.size() < 2) gt_span = gt->T_world_body;
    eval::PlotOptions po;
    po.title =
        "Trajectories from above, coloured by position error (ground truth: " + gt->kind + ")";
    po.focus_method = "full";
    warn("trajectories.png",
         eval::PlotTrajectoriesTopView({"ground truth (" + gt->kind + ")", gt_span}, methods,
                                       outages, reference, out_dir / "trajectories.png", po));
    std::vector<eval::ErrorSeries> series;
    for (const MethodEvaluation& e : evals) {
      if (e.ate) series.push_back(eval::MakeErrorSeries(e.name, e.ate->errors, reference));
    }
    if (!series.empty()) {
      eval::PlotOptions pe;
      pe.title = "Position error vs " + gt->kind + " ground truth";
      warn("position_error.png",
           eval::PlotPositionErrors(series, outages, out_dir / "position_error.png", pe));
    }
  }
  // GNSS status over time and per submap, one track per method with scans.
  std::vector<eval::GnssStatusTrack> tracks;
  for (const ModeRun& r : runs) {
    if (r.results.empty()) continue;
    // lidar_only uses no GNSS (its system still tracks the fixes); gnss_ins and
    // gnss_ins_smoothed build no submaps (their scans are placed at the POS).
    const bool uses_gnss = r.mode != MappingMode::kLidarOnly;
    const bool has_submaps =
        r.mode != MappingMode::kGnssIns && r.mode != MappingMode::kGnssInsSmoothed;
    std::vector<eval::ScanSubmap> scans;
    if (has_submaps) {
      scans.reserve(r.results.size());
      for (const LocalizationResult& res : r.results) scans.push_back({res.stamp, res.submap_id});
    }
    tracks.push_back(eval::MakeGnssStatusTrack(
        r.name, uses_gnss ? r.availability : std::vector<GnssAvailabilityInterval>(), scans,
        reference));
  }
  if (!tracks.empty()) {
    eval::PlotOptions pg;
    pg.title = "GNSS status per method: over time and per submap (worst status in the submap)";
    warn("gnss_status.png", eval::PlotGnssStatus(tracks, outages, out_dir / "gnss_status.png", pg));
  }
  for (const ModeRun& r : runs) {
    if (r.mode == MappingMode::kLidarOnly || r.map.empty()) continue;
    std::vector<Eigen::Vector3d> overlay;
    for (const StampedPose& p : r.trajectory.poses())
      overlay.push_back(p.T_world_body.translation());
    eval::PlotOptions pm;
    pm.title = "Map of " + r.name + " from above, coloured by height";
    const std::string file = "map_" + r.name + "_height.png";
    warn(file.c_str(), eval::PlotMapHeight(r.map, overlay, out_dir / file, pm));
  }
}

std::vector<std::pair<std::string, std::string>> PlotFilesOf(const std::vector<ModeRun>& runs,
                                                             const std::filesystem::path& out_dir) {
  std::vector<std::pair<std::string, std::string>> candidates = {
      {"trajectories.png",
       "Trajectories from above: one panel per method coloured by its position error against the "
       "ground truth (colour bar in metres, the ground truth in black); the last panel zooms on "
       "the largest error of full and shows every method there."},
      {"position_error.png",
       "Horizontal and vertical (up positive) position error over time, one row per method with "
       "its own scale; GNSS outages shaded where there are any."},
      {"gnss_status.png",
       "GNSS status per method over time (available, degraded, outage) and per submap (the worst "
       "status during the submap); requested outages on top."}};
  for (const ModeRun& r : runs) {
    candidates.push_back(
        {"map_" + r.name + "_height.png",
         "Map of " + r.name +
             " from above, coloured by the height of the highest point per pixel; the colour "
             "range and its clipping are stated under the title."});
  }
  std::vector<std::pair<std::string, std::string>> present;
  std::error_code ec;
  for (const auto& [file, caption] : candidates) {
    if (std::filesystem::is_regular_file(out_dir / file, ec)) present.emplace_back(file, caption);
  }
  return present;
}

std::string DescribeOutputFile(const std::string& name, const std::vector<std::string>& methods) {
  static const std::vector<std::pair<std::string, std::string>> kFixed = {
      {"report.html", "this page"},
      {"report.json",
       "every metric, the options, the input, skipped scans and the georeference, "
       "machine-readable"},
      {"summary.txt", "the metrics table as text (also printed at the end of the run)"},
      {"georef.json",
       "world origin (WGS 84), local ENU frame, output CRS (EPSG code and WKT), vertical datum, "
       "time and attitude conventions"},
      {"sim", "the simulated drive (kept by --keep-sim)"},
      {"trajectories.png", "plot: trajectories coloured by position error, zoom on the worst part"},
      {"position_error.png", "plot: horizontal and vertical position error over time"},
      {"gnss_status.png", "plot: GNSS status over time and per submap"}};
  for (const auto& [file, what] : kFixed) {
    if (name == file) return what;
  }
  if (StartsWith(name, "ground_truth") && EndsWith(name, ".tum")) {
    return "the ground truth in the run's world frame (TUM)";
  }
  // Longest method name first: "gnss_ins_smoothed" before "gnss_ins".
  std::vector<std::string> sorted = methods;
  std::sort(sorted.begin(), sorted.end(),
            [](const std::string& a, const std::string& b) { return a.size() > b.size(); });
  for (const std::string& m : sorted) {
    const std::vector<std::pair<std::string, std::string>> per_method = {
        {m + ".tum", "trajectory in the local ENU frame, TUM (t_s x y z qx qy qz qw)"},
        {m + ".kitti",
         "trajectory in the local ENU frame, KITTI 3x4 poses (their times in the times file beside "
         "it)"},
        {m + "_times.txt", "pose times of " + m + ".kitti"},
        {m + "_cov.csv", "trajectory with 6x6 pose covariances (UTC ns)"},
        {m + "_scans.csv", "per-scan results: submap, registration, degeneracy, stage timings"},
        {m + "_level1.tum", "level-1 poses before level-2 (submap) correction, TUM"},
        {m + "_wgs84.csv",
         "trajectory in WGS 84: latitude, longitude, ellipsoidal height, roll, pitch, heading, "
         "sigmas (SBET style)"},
        {m + "_utm.csv", "trajectory in WGS 84 / UTM (easting, northing, height)"},
        {m + "_projected.csv", "trajectory in the requested projected CRS"},
        {"georef_" + m + ".json", "georeference of " + m + "'s own world origin"},
        {"map_" + m + ".ply", "map point cloud in the local ENU frame, PLY"},
        {"map_" + m + ".pcd", "map point cloud in the local ENU frame, PCD"},
        {"map_" + m + ".las",
         "georeferenced map, LAS 1.4 in the output CRS (GPS time, point source ID per point)"},
        {"map_" + m + "_tiles", "georeferenced map as LAS tiles with index.json"},
        {"map_" + m + "_height.png", "plot: map of " + m + " coloured by height"}};
    for (const auto& [file, what] : per_method) {
      if (name == file) return what;
    }
    if (StartsWith(name, m + "_epsg") && EndsWith(name, ".csv")) {
      return "trajectory in the requested projected CRS (" +
             name.substr(m.size() + 1, name.size() - m.size() - 5) + ")";
    }
  }
  if (EndsWith(name, "times.txt")) return "pose times of the .kitti trajectory beside it";
  if (EndsWith(name, ".yaml")) return "configuration (YAML)";
  return "";
}

Status WriteReportHtml(const eval::EvalReport& report, const std::vector<ModeRun>& runs,
                       const std::vector<MethodEvaluation>& evals,
                       const std::vector<std::string>& warnings,
                       const std::filesystem::path& out_dir) {
  eval::HtmlReport html;
  html.title = "slam_mms run report";
  html.subtitle =
      std::string("slam_mms ") + SLAM_MMS_VERSION_STRING + " - outputs in " + out_dir.string();

  // Run summary.
  const eval::ReportInput& in = report.input;
  html.summary.emplace_back("input", in.drive + (in.kind.empty() ? "" : " (" + in.kind + ")"));
  html.summary.emplace_back("duration", Format("%.1f s", in.duration_s));
  std::string scans = std::to_string(in.scans) + " processed";
  if (in.scans_total >= 0) scans += " of " + std::to_string(in.scans_total);
  scans += ", " + std::to_string(in.skipped_scans.size()) + " skipped";
  html.summary.emplace_back("scans", scans);
  for (const ModeRun& r : runs) {
    char line[256];
    std::snprintf(line, sizeof(line),
                  "%zu of %zu scans, %zu unreadable, %d skipped by the system, %.1f s (%.2f "
                  "scans/s)%s",
                  r.scans_processed, r.scans_total, r.scans_unreadable, r.scans_skipped_by_system,
                  r.wall_s, r.scans_per_s, r.complete ? "" : ", incomplete");
    html.summary.emplace_back("method " + r.name, line);
  }
  html.summary.emplace_back("ground truth", in.ground_truth);
  std::string outages;
  for (const eval::OutageWindow& w : report.gnss_outages) {
    if (!outages.empty()) outages += "; ";
    char buf[96];
    std::snprintf(buf, sizeof(buf), "%.1f .. %.1f s (%.1f s)", w.start_s, w.start_s + w.duration_s,
                  w.duration_s);
    outages += buf;
  }
  html.summary.emplace_back("GNSS outages",
                            outages.empty() ? "none" : outages + " after the first scan");
  html.summary.emplace_back(
      "complete", report.complete ? "yes" : "no: the run stopped before the end of the drive");
  if (report.ground_truth_map_mme) {
    html.summary.emplace_back("ground-truth map MME", Format("%.4f", *report.ground_truth_map_mme));
  }
  if (!report.command_line.empty()) {
    std::string cmd;
    for (const std::string& a : report.command_line) cmd += (cmd.empty() ? "" : " ") + a;
    html.summary.emplace_back("command line", cmd);
  }

  // Warnings: main's, then what the runs carry (each once).
  std::set<std::string> seen;
  auto add_warning = [&](const std::string& w) {
    if (seen.insert(w).second) html.warnings.push_back(w);
  };
  for (const std::string& w : warnings) add_warning(w);
  for (const ModeRun& r : runs) {
    if (!r.status.ok()) add_warning(r.name + ": stopped by an error: " + r.status.ToString());
    if (r.status.ok() && !r.complete)
      add_warning(r.name + ": incomplete (the drive was not fed to the end)");
    if (r.trajectory.empty()) add_warning(r.name + ": no pose estimated");
    const size_t kMaxListed = 20;
    for (size_t i = 0; i < r.skipped_scans.size() && i < kMaxListed; ++i) {
      add_warning(r.name + ": skipped scan: " + r.skipped_scans[i]);
    }
    if (r.skipped_scans.size() > kMaxListed) {
      add_warning(r.name + ": ... and " + std::to_string(r.skipped_scans.size() - kMaxListed) +
                  " more skipped scans (report.json lists them all)");
    }
  }
  for (const eval::SkippedScan& s : in.skipped_scans) {
    if (seen.size() > 200) break;
    add_warning("skipped scan " + s.source + ": " + s.reason);
  }
  if (in.ground_truth == "none")
    add_warning("no ground truth: the error metrics and plots are absent");
  if (report.georef_json.empty()) {
    add_warning("world origin unknown: the outputs are not georeferenced (no georef.json)");
  }

  // Metrics.
  html.metrics.header = {"method",
                         "ATE [m]",
                         "ATE horiz. [m]",
                         "ATE vert. [m]",
                         "rot. RMSE [deg]",
                         "t_rel [%]",
                         "r_rel [deg/100 m]",
                         "max err. in outages [m]",
                         "MME",
                         "scans/s",
                         "peak RSS [MB]"};
  std::string notes;
  for (const MethodEvaluation& e : evals) {
    const eval::MethodReport& m = e.report;
    std::optional<double> h, v;
    if (m.ate_rmse_xyz_m) {
      h = m.ate_rmse_xyz_m->head<2>().norm();
      v = m.ate_rmse_xyz_m->z();
    }
    html.metrics.rows.push_back({e.name, Cell(m.ate_rmse_m, "%.3f"), Cell(h, "%.3f"),
                                 Cell(v, "%.3f"), Cell(m.rot_rmse_deg, "%.3f"),
                                 Cell(m.t_rel_pct, "%.3f"), Cell(m.r_rel_deg_per_100m, "%.4f"),
                                 Cell(m.max_pos_err_in_outage_m, "%.3f"), Cell(m.mme, "%.4f"),
                                 Cell(m.scans_per_s, "%.2f"), Cell(m.peak_rss_mb, "%.0f")});
    if (!e.relative_label.empty()) {
      notes += " " + e.name + ": t_rel/r_rel over segments " + e.relative_label + " (" +
               std::to_string(e.relative_segments) + " segments), " +
               std::to_string(e.outage_poses) + " poses inside GNSS outages, MME over " +
               std::to_string(e.mme_points) + " points.";
    }
  }
  html.metrics.note = "ATE and rotation RMSE without alignment, against the " + in.ground_truth +
                      " ground truth at each scan's start; horizontal = RMS of the east/north "
                      "error, vertical = RMS of the up error; '-' = not computed." +
                      notes;

  // Plots.
  for (const auto& [file, caption] : PlotFilesOf(runs, out_dir)) {
    html.images.push_back({caption, out_dir / file});
  }

  // Georeference.
  if (!report.georef_json.empty()) {
    const nlohmann::ordered_json j =
        nlohmann::ordered_json::parse(report.georef_json, nullptr, false);
    if (j.is_object()) {
      FlattenJson(j, "", &html.georeference);
      html.georeference_note =
          "The TUM, KITTI, PLY and PCD outputs are in the local ENU frame above; the LAS maps and "
          "the *_wgs84 / projected CSV trajectories are georeferenced. georef.json holds all of "
          "it, with the full WKT.";
    } else {
      html.georeference_note = "georef.json could not be parsed; see the file itself.";
    }
  } else {
    html.georeference_note =
        "World origin unknown (no valid GNSS fix): the outputs are in an arbitrary local frame.";
  }

  // Output files: what out_dir holds now, plus this page.
  std::vector<std::string> method_names;
  for (const ModeRun& r : runs) method_names.push_back(r.name);
  std::set<std::string> names = {"report.html"};
  std::error_code ec;
  for (std::filesystem::directory_iterator it(out_dir, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.empty() || name[0] == '.' || EndsWith(name, ".tmp")) continue;
    names.insert(it->is_directory() ? name + "/" : name);
  }
  for (const std::string& name : names) {
    const bool dir = EndsWith(name, "/");
    std::string what =
        DescribeOutputFile(dir ? name.substr(0, name.size() - 1) : name, method_names);
    if (what.empty()) what = dir ? "folder" : "";
    html.files.push_back({name, what});
  }
  return eval::WriteHtmlReport(html, out_dir / "report.html");
}

}  // namespace slam_mms::app
