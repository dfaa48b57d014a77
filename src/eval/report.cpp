#include "slam_mms/eval/report.hpp"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "slam_mms/version.hpp"

namespace slam_mms::eval {
namespace {

using Json = nlohmann::ordered_json;

std::optional<double> Finite(double v) {
  return std::isfinite(v) ? std::optional<double>(v) : std::nullopt;
}

// A number, or null for nullopt and non-finite values.
Json Number(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? Json(*v) : Json(nullptr);
}

Json Vector(const std::optional<Eigen::Vector3d>& v) {
  if (!v) return nullptr;
  Json a = Json::array();
  for (int k = 0; k < 3; ++k) a.push_back(Number((*v)(k)));
  return a;
}

// An embedded object from the caller's text: null when empty, an error when not a JSON object.
StatusOr<Json> EmbeddedObject(const std::string& text, const char* field) {
  if (text.empty()) return Json(nullptr);
  Json j = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) {
    return InvalidArgumentError(std::string("EvalReport::") + field +
                                " is not valid JSON: " + text.substr(0, 80));
  }
  if (!j.is_object()) {
    return InvalidArgumentError(std::string("EvalReport::") + field +
                                " must be a JSON object, got " + j.type_name());
  }
  return j;
}

}  // namespace

MethodReport MakeMethodReport(const AteResult* ate, const RelativeErrorResult* relative,
                              const OutageErrorResult* outage, const MapEntropyResult* entropy,
                              const NeesResult* nees) {
  MethodReport m;
  if (nees != nullptr && nees->num_epochs > 0) m.nees = *nees;
  if (ate != nullptr) {
    m.ate_rmse_m = ate->ate_rmse_m;
    m.ate_rmse_xyz_m = ate->ate_rmse_xyz_m;
    m.rot_rmse_deg = ate->rot_rmse_deg;
    m.rot_rmse_rpy_deg = ate->rot_rmse_rpy_deg;
    m.rot_mean_rpy_deg = ate->rot_mean_rpy_deg;
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

ReferenceMetrics MakeReferenceMetrics(const AteResult* ate, const RelativeErrorResult* relative,
                                      const OutageErrorResult* outage) {
  const MethodReport m = MakeMethodReport(ate, relative, outage, nullptr);
  ReferenceMetrics r;
  r.ate_rmse_m = m.ate_rmse_m;
  r.rot_rmse_deg = m.rot_rmse_deg;
  r.t_rel_pct = m.t_rel_pct;
  r.r_rel_deg_per_100m = m.r_rel_deg_per_100m;
  r.max_pos_err_in_outage_m = m.max_pos_err_in_outage_m;
  return r;
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
  if (!report.input.kind.empty() && report.input.kind != "kitti_raw" &&
      report.input.kind != "folder" && report.input.kind != "rosbag" &&
      report.input.kind != "simulated") {
    return InvalidArgumentError("EvalReport::input.kind = \"" + report.input.kind +
                                "\"; must be \"kitti_raw\", \"folder\", \"rosbag\", "
                                "\"simulated\" or empty");
  }
  SLAM_MMS_ASSIGN_OR_RETURN(Json options, EmbeddedObject(report.options_json, "options_json"));
  SLAM_MMS_ASSIGN_OR_RETURN(Json georef, EmbeddedObject(report.georef_json, "georef_json"));
  SLAM_MMS_ASSIGN_OR_RETURN(Json extrinsics,
                            EmbeddedObject(report.extrinsics_json, "extrinsics_json"));

  Json j = Json::object();
  j["version"] = SLAM_MMS_VERSION_STRING;
  j["complete"] = report.complete;
  j["command_line"] = report.command_line;
  const ReportInput& in = report.input;
  Json input = Json::object();
  input["drive"] = in.drive;
  input["kind"] = in.kind.empty() ? Json(nullptr) : Json(in.kind);
  input["scans"] = in.scans;
  input["scans_total"] = in.scans_total < 0 ? Json(nullptr) : Json(in.scans_total);
  input["scans_processed"] = in.scans;
  input["duration_s"] = Number(in.duration_s);
  input["ground_truth"] = in.ground_truth;
  Json skipped = Json::array();
  for (const SkippedScan& s : in.skipped_scans) {
    skipped.push_back(Json{{"source", s.source}, {"reason", s.reason}});
  }
  input["skipped_scans"] = Json{{"count", in.skipped_scans.size()}, {"scans", skipped}};
  input["imu_noise"] = in.imu_noise.empty() ? Json(nullptr) : Json(in.imu_noise);
  input["oxts_inertial_delay_s"] =
      in.oxts_inertial_delay_s ? Number(*in.oxts_inertial_delay_s) : Json(nullptr);
  j["input"] = std::move(input);

  Json outages = Json::array();
  for (const OutageWindow& o : report.gnss_outages) {
    outages.push_back(Json::array({Number(o.start_s), Number(o.duration_s)}));
  }
  j["gnss_outages"] = std::move(outages);

  Json methods = Json::object();
  for (const auto& [name, m] : report.methods) {
    Json jm = Json::object();
    jm["ate_rmse_m"] = Number(m.ate_rmse_m);
    jm["ate_rmse_xyz_m"] = Vector(m.ate_rmse_xyz_m);
    jm["rot_rmse_deg"] = Number(m.rot_rmse_deg);
    jm["rot_rmse_rpy_deg"] = Vector(m.rot_rmse_rpy_deg);
    jm["rot_mean_rpy_deg"] = Vector(m.rot_mean_rpy_deg);
    jm["t_rel_pct"] = Number(m.t_rel_pct);
    jm["r_rel_deg_per_100m"] = Number(m.r_rel_deg_per_100m);
    jm["max_pos_err_in_outage_m"] = Number(m.max_pos_err_in_outage_m);
    jm["max_rot_err_in_outage_deg"] = Number(m.max_rot_err_in_outage_deg);
    jm["mme"] = Number(m.mme);
    if (m.nees) {
      jm["nees"] = Json{{"epochs", m.nees->num_epochs},
                        {"position_mean", Number(m.nees->position_mean)},
                        {"position_inside_95", Number(m.nees->position_fraction_inside_95)},
                        {"attitude_mean", Number(m.nees->attitude_mean)},
                        {"attitude_inside_95", Number(m.nees->attitude_fraction_inside_95)}};
    } else {
      jm["nees"] = nullptr;
    }
    jm["scans_per_s"] = Number(m.scans_per_s);
    jm["peak_rss_mb"] = Number(m.peak_rss_mb);
    if (m.vs_oxts_velocity) {
      const ReferenceMetrics& r = *m.vs_oxts_velocity;
      jm["vs_oxts_velocity"] = Json{{"ate_rmse_m", Number(r.ate_rmse_m)},
                                    {"rot_rmse_deg", Number(r.rot_rmse_deg)},
                                    {"t_rel_pct", Number(r.t_rel_pct)},
                                    {"r_rel_deg_per_100m", Number(r.r_rel_deg_per_100m)},
                                    {"max_pos_err_in_outage_m", Number(r.max_pos_err_in_outage_m)}};
    } else {
      jm["vs_oxts_velocity"] = nullptr;
    }
    methods[name] = std::move(jm);
  }
  j["methods"] = std::move(methods);
  j["ground_truth_map"] = Json{{"mme", Number(report.ground_truth_map_mme)}};
  j["options"] = std::move(options);
  j["georef"] = std::move(georef);
  j["extrinsics"] = std::move(extrinsics);
  j["warnings"] = report.warnings;
  if (!report.outputs.empty()) j["outputs"] = Json{{"files", report.outputs}};
  // Invalid UTF-8 in a path or message is replaced rather than failing the whole report.
  return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
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
