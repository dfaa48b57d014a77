#include "slam_mms_run/checkpoint.hpp"

#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "slam_mms/io/map_io.hpp"
#include "slam_mms_run/json_file.hpp"

namespace slam_mms::app {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

constexpr const char* kFormat = "slam_mms_run checkpoint";
constexpr int kFormatVersion = 1;

template <typename Derived>
Json Matrix(const Eigen::MatrixBase<Derived>& m) {
  Json a = Json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) a.push_back(m(r, c));
  }
  return a;
}

template <typename M>
bool ReadMatrix(const Json& a, M* m) {
  if (!a.is_array() || a.size() != static_cast<size_t>(m->rows() * m->cols())) return false;
  size_t k = 0;
  for (Eigen::Index r = 0; r < m->rows(); ++r) {
    for (Eigen::Index c = 0; c < m->cols(); ++c) (*m)(r, c) = a.at(k++).get<double>();
  }
  return true;
}

Json PoseJson(const Eigen::Isometry3d& T) { return Matrix(T.matrix().topRows<3>()); }

bool ReadPose(const Json& a, Eigen::Isometry3d* T) {
  Eigen::Matrix<double, 3, 4> m;
  if (!ReadMatrix(a, &m)) return false;
  T->setIdentity();
  T->matrix().topRows<3>() = m;
  return true;
}

Json ResultJson(const LocalizationResult& r) {
  return Json{{"scan_index", r.scan_index},
              {"stamp_ns", r.stamp.nanoseconds()},
              {"submap_id", r.submap_id},
              {"new_submap", r.new_submap},
              {"T_world_body", PoseJson(r.T_world_body)},
              {"cov_T_world_body", Matrix(r.cov_T_world_body)},
              {"motion_factor", static_cast<int>(r.motion_factor)},
              {"registered", r.registered},
              {"registration_used", r.registration_used},
              {"registration_downweighted", r.registration_downweighted},
              {"termination", static_cast<int>(r.termination)},
              {"num_inliers", r.num_inliers},
              {"inlier_ratio", r.inlier_ratio},
              {"rms_residual_m", r.rms_residual_m},
              {"icp_iterations", r.icp_iterations},
              {"degenerate", r.degenerate},
              {"degeneracy_axis_information", Matrix(r.degeneracy_axis_information)},
              {"consistency_mahalanobis_sq", r.consistency_mahalanobis_sq},
              {"num_surfels", r.num_surfels},
              {"num_model_surfels", r.num_model_surfels},
              {"num_moving_objects", r.num_moving_objects},
              {"num_moving_pixels", r.num_moving_pixels},
              {"timings_ms", r.timings.Values()},
              {"total_ms", r.timings.total_ms}};
}

bool ReadResult(const Json& j, LocalizationResult* r) {
  r->scan_index = j.at("scan_index").get<int64_t>();
  r->stamp = Timestamp::FromNanoseconds(j.at("stamp_ns").get<int64_t>());
  r->submap_id = j.at("submap_id").get<int32_t>();
  r->new_submap = j.at("new_submap").get<bool>();
  if (!ReadPose(j.at("T_world_body"), &r->T_world_body)) return false;
  if (!ReadMatrix(j.at("cov_T_world_body"), &r->cov_T_world_body)) return false;
  r->motion_factor = static_cast<MotionFactorType>(j.at("motion_factor").get<int>());
  r->registered = j.at("registered").get<bool>();
  r->registration_used = j.at("registration_used").get<bool>();
  r->registration_downweighted = j.at("registration_downweighted").get<bool>();
  r->termination = static_cast<IcpTermination>(j.at("termination").get<int>());
  r->num_inliers = j.at("num_inliers").get<size_t>();
  r->inlier_ratio = j.at("inlier_ratio").get<double>();
  r->rms_residual_m = j.at("rms_residual_m").get<double>();
  r->icp_iterations = j.at("icp_iterations").get<int>();
  r->degenerate = j.at("degenerate").get<bool>();
  if (!ReadMatrix(j.at("degeneracy_axis_information"), &r->degeneracy_axis_information)) {
    return false;
  }
  r->consistency_mahalanobis_sq = j.at("consistency_mahalanobis_sq").get<double>();
  r->num_surfels = j.at("num_surfels").get<size_t>();
  r->num_model_surfels = j.at("num_model_surfels").get<size_t>();
  r->num_moving_objects = j.value("num_moving_objects", 0);
  r->num_moving_pixels = j.value("num_moving_pixels", 0);
  const auto t = j.at("timings_ms").get<std::vector<double>>();
  if (t.size() != StageTimings::kNumStages) return false;
  StageTimings& s = r->timings;
  s.deskew_ms = t[0];
  s.predict_ms = t[1];
  s.render_ms = t[2];
  s.register_ms = t[3];
  s.factors_ms = t[4];
  s.optimize_ms = t[5];
  s.integrate_ms = t[6];
  s.total_ms = j.at("total_ms").get<double>();
  return true;
}

// The finished method, without its map.
Json RunJson(const ModeRun& run) {
  Json traj = Json::array();
  for (const StampedPose& p : run.trajectory.poses()) {
    traj.push_back(Json{{"stamp_ns", p.stamp.nanoseconds()},
                        {"T_world_body", PoseJson(p.T_world_body)},
                        {"cov", p.cov_T_world_body ? Matrix(*p.cov_T_world_body) : Json(nullptr)}});
  }
  Json results = Json::array();
  for (const LocalizationResult& r : run.results) results.push_back(ResultJson(r));
  Json availability = Json::array();
  for (const GnssAvailabilityInterval& a : run.availability) {
    availability.push_back(Json{{"start_ns", a.start.nanoseconds()},
                                {"end_ns", a.end.nanoseconds()},
                                {"availability", static_cast<int>(a.availability)}});
  }
  Json j;
  j["mode"] = run.name;
  j["origin"] =
      run.origin
          ? Json::array({run.origin->latitude_deg, run.origin->longitude_deg, run.origin->height_m})
          : Json(nullptr);
  j["first_scan_start_ns"] =
      run.first_scan_start ? Json(run.first_scan_start->nanoseconds()) : Json(nullptr);
  j["wall_s"] = run.wall_s;
  j["scans_total"] = run.scans_total;
  j["scans_processed"] = run.scans_processed;
  j["scans_unreadable"] = run.scans_unreadable;
  j["scans_skipped_by_system"] = run.scans_skipped_by_system;
  j["skipped_scans"] = run.skipped_scans;
  j["scans_per_s"] = run.scans_per_s;
  j["peak_rss_mb"] = run.peak_rss_mb ? Json(*run.peak_rss_mb) : Json(nullptr);
  j["finished"] = run.finished;
  j["complete"] = run.complete;
  j["smoothed_pos"] = run.smoothed_pos;
  j["availability"] = std::move(availability);
  j["trajectory"] = std::move(traj);
  j["results"] = std::move(results);
  return j;
}

Status ReadRun(const Json& j, const std::string& where, ModeRun* run) {
  auto bad = [&](const std::string& what) {
    return DataLossError(where + ": " + what + " is missing or malformed");
  };
  if (!ParseMappingMode(j.at("mode").get<std::string>(), &run->mode)) return bad("\"mode\"");
  run->name = MappingModeName(run->mode);
  if (!j.at("origin").is_null()) {
    const auto o = j.at("origin").get<std::vector<double>>();
    if (o.size() != 3) return bad("\"origin\"");
    run->origin = GeodeticPoint{o[0], o[1], o[2]};
  }
  if (!j.at("first_scan_start_ns").is_null()) {
    run->first_scan_start = Timestamp::FromNanoseconds(j.at("first_scan_start_ns").get<int64_t>());
  }
  run->wall_s = j.at("wall_s").get<double>();
  run->scans_total = j.at("scans_total").get<size_t>();
  run->scans_processed = j.at("scans_processed").get<size_t>();
  run->scans_unreadable = j.at("scans_unreadable").get<size_t>();
  run->scans_skipped_by_system = j.at("scans_skipped_by_system").get<int>();
  run->skipped_scans = j.at("skipped_scans").get<std::vector<std::string>>();
  run->scans_per_s = j.at("scans_per_s").get<double>();
  if (!j.at("peak_rss_mb").is_null()) run->peak_rss_mb = j.at("peak_rss_mb").get<double>();
  run->finished = j.at("finished").get<bool>();
  run->complete = j.at("complete").get<bool>();
  run->smoothed_pos = j.at("smoothed_pos").get<bool>();
  for (const Json& a : j.at("availability")) {
    run->availability.push_back({Timestamp::FromNanoseconds(a.at("start_ns").get<int64_t>()),
                                 Timestamp::FromNanoseconds(a.at("end_ns").get<int64_t>()),
                                 static_cast<GnssAvailability>(a.at("availability").get<int>())});
  }
  for (const Json& p : j.at("trajectory")) {
    StampedPose pose;
    pose.stamp = Timestamp::FromNanoseconds(p.at("stamp_ns").get<int64_t>());
    if (!ReadPose(p.at("T_world_body"), &pose.T_world_body)) return bad("a trajectory pose");
    if (!p.at("cov").is_null()) {
      Eigen::Matrix<double, 6, 6> cov;
      if (!ReadMatrix(p.at("cov"), &cov)) return bad("a trajectory covariance");
      pose.cov_T_world_body = cov;
    }
    SLAM_MMS_RETURN_IF_ERROR(run->trajectory.Add(pose).WithContext(where));
  }
  for (const Json& r : j.at("results")) {
    LocalizationResult result;
    if (!ReadResult(r, &result)) return bad("a per-scan result");
    run->results.push_back(result);
  }
  return OkStatus();
}

Json FingerprintJson(const RunFingerprint& fingerprint) {
  Json j = Json::object();
  for (const auto& [k, v] : fingerprint) {
    Json value = Json::parse(v, nullptr, false);
    j[k] = value.is_discarded() ? Json(v) : value;
  }
  return j;
}

}  // namespace

StatusOr<Checkpoint> Checkpoint::Start(const fs::path& out_dir, const RunFingerprint& fingerprint) {
  Checkpoint c;
  c.dir_ = out_dir / "checkpoint";
  std::error_code ec;
  fs::remove_all(c.dir_, ec);
  fs::create_directories(c.dir_, ec);
  if (ec) return UnavailableError("cannot create " + c.dir_.string() + ": " + ec.message());
  c.fingerprint_json_ = FingerprintJson(fingerprint).dump();
  SLAM_MMS_RETURN_IF_ERROR(c.WriteRunJson());
  return c;
}

StatusOr<Checkpoint> Checkpoint::Resume(const fs::path& out_dir,
                                        const RunFingerprint& fingerprint) {
  Checkpoint c;
  c.dir_ = out_dir / "checkpoint";
  const fs::path file = c.dir_ / "run.json";
  std::error_code ec;
  if (!fs::exists(file, ec)) {
    return NotFoundError("--resume: no checkpoint in " + out_dir.string() + " (" + file.string() +
                         " does not exist)");
  }
  SLAM_MMS_ASSIGN_OR_RETURN(const Json j, ReadJsonFile(file));
  if (!j.is_object() || j.value("format", "") != kFormat ||
      j.value("format_version", 0) != kFormatVersion || !j.contains("fingerprint") ||
      !j.contains("methods") || !j["methods"].is_object()) {
    return InvalidArgumentError(file.string() + ": not a slam_mms_run checkpoint of format " +
                                std::to_string(kFormatVersion));
  }
  const Json now = FingerprintJson(fingerprint);
  const Json& then = j["fingerprint"];
  for (const auto& [key, value] : now.items()) {
    if (!then.contains(key) || then[key] != value) {
      return InvalidArgumentError(
          "--resume: the checkpoint in " + out_dir.string() + " is of a different run: " + key +
          " was " + (then.contains(key) ? then[key].dump() : std::string("absent")) + ", is now " +
          value.dump() + " (run without --resume to start again)");
    }
  }
  c.fingerprint_json_ = now.dump();
  c.methods_json_ = j["methods"].dump();
  return c;
}

bool Checkpoint::HasFinished(const std::string& name) const {
  const Json m = Json::parse(methods_json_);
  return m.contains(name) && m[name].value("state", "") == "complete";
}

StatusOr<ModeRun> Checkpoint::LoadFinished(const std::string& name) const {
  const fs::path file = dir_ / (name + ".json");
  SLAM_MMS_ASSIGN_OR_RETURN(const Json j, ReadJsonFile(file));
  ModeRun run;
  try {
    SLAM_MMS_RETURN_IF_ERROR(ReadRun(j, file.string(), &run));
  } catch (const Json::exception& e) {
    return DataLossError(file.string() + ": " + e.what());
  }
  const fs::path map_file = dir_ / (name + "_map.ply");
  std::error_code ec;
  if (fs::exists(map_file, ec)) {
    SLAM_MMS_ASSIGN_OR_RETURN(MapCloud map, ReadPly(map_file));
    run.map = std::move(map.cloud);
  }
  return run;
}

Status Checkpoint::SaveFinished(const ModeRun& run, const fs::path& written_map_ply) {
  SLAM_MMS_RETURN_IF_ERROR(WriteJsonFile(RunJson(run), dir_ / (run.name + ".json"), 1));
  if (!run.map.empty()) {
    const fs::path file = dir_ / (run.name + "_map.ply");
    std::error_code ec;
    fs::remove(file, ec);
    bool linked = false;
    if (!written_map_ply.empty()) {
      fs::create_hard_link(written_map_ply, file, ec);
      linked = !ec;
    }
    if (!linked) {
      MapCloud map;
      map.cloud = run.map;
      SLAM_MMS_RETURN_IF_ERROR(WritePly(map, file));
    }
  }
  Json m = Json::parse(methods_json_);
  m[run.name] = Json{{"state", "complete"}, {"scans_fed", run.scans_total}};
  methods_json_ = m.dump();
  return WriteRunJson();
}

Status Checkpoint::SaveProgress(const std::string& name, size_t scans_fed, int submaps) {
  Json m = Json::parse(methods_json_);
  m[name] = Json{{"state", "in_progress"}, {"scans_fed", scans_fed}, {"submaps", submaps}};
  methods_json_ = m.dump();
  return WriteRunJson();
}

void Checkpoint::Remove() {
  std::error_code ec;
  fs::remove_all(dir_, ec);
}

Status Checkpoint::WriteRunJson() const {
  Json j;
  j["format"] = kFormat;
  j["format_version"] = kFormatVersion;
  j["fingerprint"] = Json::parse(fingerprint_json_);
  j["methods"] = Json::parse(methods_json_);
  return WriteJsonFile(j, dir_ / "run.json", 1);
}

}  // namespace slam_mms::app
