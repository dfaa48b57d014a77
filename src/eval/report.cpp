#include "slam_mms/eval/report.hpp"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "slam_mms/eval/json_writer.hpp"

namespace slam_mms::eval {
namespace {

std::optional<double> Finite(double v) {
  return std::isfinite(v) ? std::optional<double>(v) : std::nullopt;
}

void WriteVector(JsonWriter& w, const std::optional<Eigen::Vector3d>& v) {
  if (!v) {
    w.Null();
    return;
  }
  w.BeginArray();
  for (int k = 0; k < 3; ++k) w.Number((*v)(k));
  w.EndArray();
}

}  // namespace

MethodReport MakeMethodReport(const AteResult* ate, const RelativeErrorResult* relative,
                              const OutageErrorResult* outage, const MapEntropyResult* entropy) {
  MethodReport m;
  if (ate != nullptr) {
    m.ate_rmse_m = ate->ate_rmse_m;
    m.ate_rmse_xyz_m = ate->ate_rmse_xyz_m;
    m.rot_rmse_deg = ate->rot_rmse_deg;
    m.rot_rmse_rpy_deg = ate->rot_rmse_rpy_deg;
  }
  if (relative != nullptr && relative->num_segments > 0) {
    m.t_rel_pct = Finite(relative->t_rel_pct);
    m.r_rel_deg_per_100m = Finite(relative->r_rel_deg_per_100m);
  }
  if (outage != nullptr && outage->num_poses > 0) {
    m.max_pos_err_in_outage_m = outage->max_pos_err_m;
    m.max_rot_err_in_outage_deg = outage->max_rot_err_deg;
  }
  if (entropy != nullptr) m.mme = Finite(entropy->mean_map_entropy);
  return m;
}

bool IsReportMethodName(const std::string& name) {
  return name == "full" || name == "gnss_ins" || name == "gnss_ins_smoothed" ||
         name == "lidar_only";
}

StatusOr<std::string> ReportToJson(const EvalReport& report) {
  if (report.input.ground_truth != "simulator" && report.input.ground_truth != "oxts" &&
      report.input.ground_truth != "none") {
    return InvalidArgumentError("EvalReport::input.ground_truth = \"" + report.input.ground_truth +
                                "\"; must be \"simulator\", \"oxts\" or \"none\"");
  }
  std::set<std::string> seen;
  for (const auto& [name, m] : report.methods) {
    if (!IsReportMethodName(name)) {
      return InvalidArgumentError("EvalReport::methods has \"" + name +
                                  "\"; must be \"full\", \"gnss_ins\", \"gnss_ins_smoothed\" or "
                                  "\"lidar_only\"");
    }
    if (!seen.insert(name).second) {
      return InvalidArgumentError("EvalReport::methods has \"" + name + "\" twice");
    }
  }
  JsonWriter w;
  w.BeginObject();
  w.Key("input").BeginObject();
  w.Key("drive").String(report.input.drive);
  w.Key("scans").Int(report.input.scans);
  w.Key("duration_s").Number(report.input.duration_s);
  w.Key("ground_truth").String(report.input.ground_truth);
  w.EndObject();

  w.Key("gnss_outages").BeginArray();
  for (const OutageWindow& o : report.gnss_outages) {
    w.BeginArray().Number(o.start_s).Number(o.duration_s).EndArray();
  }
  w.EndArray();

  w.Key("methods").BeginObject();
  for (const auto& [name, m] : report.methods) {
    w.Key(name).BeginObject();
    w.Key("ate_rmse_m").Number(m.ate_rmse_m);
    w.Key("ate_rmse_xyz_m");
    WriteVector(w, m.ate_rmse_xyz_m);
    w.Key("rot_rmse_deg").Number(m.rot_rmse_deg);
    w.Key("rot_rmse_rpy_deg");
    WriteVector(w, m.rot_rmse_rpy_deg);
    w.Key("t_rel_pct").Number(m.t_rel_pct);
    w.Key("r_rel_deg_per_100m").Number(m.r_rel_deg_per_100m);
    w.Key("max_pos_err_in_outage_m").Number(m.max_pos_err_in_outage_m);
    w.Key("max_rot_err_in_outage_deg").Number(m.max_rot_err_in_outage_deg);
    w.Key("mme").Number(m.mme);
    w.Key("scans_per_s").Number(m.scans_per_s);
    w.Key("peak_rss_mb").Number(m.peak_rss_mb);
    w.EndObject();
  }
  w.EndObject();

  w.Key("ground_truth_map").BeginObject();
  w.Key("mme").Number(report.ground_truth_map_mme);
  w.EndObject();
  w.EndObject();
  return w.Finish();
}

Status WriteReportJson(const EvalReport& report, const std::filesystem::path& path) {
  SLAM_MMS_ASSIGN_OR_RETURN(std::string text, ReportToJson(report));
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return NotFoundError("cannot open " + path.string() + " for writing");
  out << text;
  out.close();
  if (!out) return DataLossError("failed writing " + path.string());
  return OkStatus();
}

std::optional<double> PeakRssMb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      std::istringstream s(line.substr(6));
      double kb = 0.0;
      if (s >> kb) return kb / 1024.0;
    }
  }
  return std::nullopt;
}

}  // namespace slam_mms::eval
