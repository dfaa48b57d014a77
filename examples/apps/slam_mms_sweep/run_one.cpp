#include "slam_mms_sweep/run_one.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/drive/extrinsic_calibrator.hpp"
#include "slam_mms/drive/open_drive.hpp"
#include "slam_mms/eval/ground_truth.hpp"
#include "slam_mms/eval/relative_error.hpp"
#include "slam_mms/eval/trajectory_error.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms_run/calibration.hpp"
#include "slam_mms_run/config_file.hpp"
#include "slam_mms_run/json_file.hpp"
#include "slam_mms_run/outputs.hpp"
#include "slam_mms_run/progress.hpp"
#include "slam_mms_run/run_mode.hpp"

namespace slam_mms::sweep {
namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

Json Opt(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? Json(*v) : Json(nullptr);
}

bool Finite(const Eigen::Isometry3d& T) { return T.matrix().allFinite(); }

void ApplyScenario(const SweepRun& run, sim::DriveSimulator::Options* o) {
  using sim::GnssState;
  switch (run.scenario) {
    case GnssScenario::kFixed:
      o->gnss.best_state = GnssState::kRtkFixed;
      o->gnss.urban_canyon_scale = 0.0;
      break;
    case GnssScenario::kCanyon:
    case GnssScenario::kOutage: o->gnss.best_state = GnssState::kRtkFixed; break;
    case GnssScenario::kFloat:
      o->gnss.best_state = GnssState::kRtkFloat;
      o->gnss.urban_canyon_scale = 0.0;
      break;
    case GnssScenario::kSps:
      o->gnss.best_state = GnssState::kSps;
      o->gnss.urban_canyon_scale = 0.0;
      break;
  }
}

int Fail(const fs::path& run_dir, const Json& spec, const Status& s) {
  std::fprintf(stderr, "slam_mms_sweep --run-one: %s\n", s.ToString().c_str());
  Json j{{"spec", spec}, {"error", s.ToString()}};
  (void)app::WriteJsonFile(j, run_dir / "result.json", 2);
  return 1;
}

// The largest position error after aligning the estimate's first pose with the ground truth's
// (the relative-pose error from the start): the drift of the method itself, without the error of
// the initial state it was given. Null without ground truth.
std::optional<double> MaxDriftFromStart(const Trajectory& estimate, const eval::GroundTruth* gt) {
  if (gt == nullptr || estimate.size() < 2) return std::nullopt;
  StatusOr<eval::MatchedPoses> m = eval::MatchByTimestamp(estimate, gt->T_world_body);
  if (!m.ok() || m->size() < 2) return std::nullopt;
  const Eigen::Isometry3d gt0_inv = m->T_world_gt[0].inverse();
  const Eigen::Isometry3d est0_inv = m->T_world_est[0].inverse();
  double worst = 0.0;
  for (size_t i = 1; i < m->size(); ++i) {
    const Eigen::Isometry3d d =
        (gt0_inv * m->T_world_gt[i]).inverse() * (est0_inv * m->T_world_est[i]);
    worst = std::max(worst, d.translation().norm());
  }
  return worst;
}

// One method's numbers (see the file comment of run_one.hpp).
Json MethodJson(const app::ModeRun& run, const app::MethodEvaluation& ev,
                const eval::GroundTruth* gt) {
  const eval::MethodReport& m = ev.report;
  bool finite = true;
  for (const StampedPose& p : run.trajectory.poses()) finite = finite && Finite(p.T_world_body);
  for (const LocalizationResult& r : run.results) finite = finite && Finite(r.T_world_body);
  for (const Eigen::Vector3f& p : run.map.points()) finite = finite && p.allFinite();
  size_t registered = 0, degenerate = 0;
  for (const LocalizationResult& r : run.results) {
    if (!r.registered) continue;
    ++registered;
    if (r.degenerate) ++degenerate;
  }
  std::optional<double> max_err;
  if (ev.ate) max_err = ev.ate->ate_max_m;
  return Json{
      {"status", run.status.ok() ? "ok" : run.status.ToString()},
      {"complete", run.complete},
      {"finite", finite},
      {"scans_processed", run.scans_processed},
      {"scans_total", run.scans_total},
      {"skipped_scans", run.skipped_scans.size()},
      {"ate_rmse_m", Opt(m.ate_rmse_m)},
      {"rot_rmse_deg", Opt(m.rot_rmse_deg)},
      {"t_rel_pct", Opt(m.t_rel_pct)},
      {"r_rel_deg_per_100m", Opt(m.r_rel_deg_per_100m)},
      {"max_pos_err_m", Opt(max_err)},
      {"max_drift_from_start_m", Opt(MaxDriftFromStart(run.trajectory, gt))},
      {"max_pos_err_in_outage_m", Opt(m.max_pos_err_in_outage_m)},
      {"max_rot_err_in_outage_deg", Opt(m.max_rot_err_in_outage_deg)},
      {"mme", Opt(m.mme)},
      {"degenerate_fraction",
       registered > 0 ? Json(static_cast<double>(degenerate) / registered) : Json(nullptr)},
      {"scans_per_s", run.scans_per_s},
      {"wall_s", run.wall_s},
  };
}

// Level 2's relative factors of a drive (reckon, map-to-map registration, loop) as added, with
// the times of their two submaps' references (their first scans; the reference is the body at
// that scan, T_submap_scan of it maps it to the submap frame).
struct RelativeFactorRecord {
  SubmapFactorKind kind = SubmapFactorKind::kReckon;
  SubmapId a = 0, b = 0;
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Identity();
  Timestamp stamp_a, stamp_b;
  Eigen::Isometry3d T_submap_scan_a = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_submap_scan_b = Eigen::Isometry3d::Identity();
};

std::vector<RelativeFactorRecord> RelativeFactors(const DriveResult& drive) {
  std::map<SubmapId, const DriveSubmap*> by_id;
  for (const DriveSubmap& s : drive.submaps) {
    if (!s.scans.empty()) by_id[s.id] = &s;
  }
  std::vector<RelativeFactorRecord> out;
  for (const SubmapGraphFactor& f : drive.factors) {
    if (f.kind != SubmapFactorKind::kReckon && f.kind != SubmapFactorKind::kRegistration &&
        f.kind != SubmapFactorKind::kLoop) {
      continue;
    }
    const auto a = by_id.find(f.a), b = by_id.find(f.b);
    if (a == by_id.end() || b == by_id.end()) continue;
    out.push_back({f.kind, f.a, f.b, f.T, f.covariance, a->second->scans.front().stamp,
                   b->second->scans.front().stamp, a->second->scans.front().T_submap_scan,
                   b->second->scans.front().T_submap_scan});
  }
  return out;
}

// Each factor against the truth (eval::RelativePoseErrorAgainstTruth): the honesty of what level
// 2 is told, over every drive of the sweep (sweep.md, "Level 2's relative factors").
Json RelativeFactorsJson(const std::vector<RelativeFactorRecord>& factors,
                         const eval::GroundTruth& gt) {
  Json out = Json::array();
  for (const RelativeFactorRecord& f : factors) {
    StatusOr<Eigen::Isometry3d> body_a = gt.T_world_body.Interpolate(f.stamp_a);
    StatusOr<Eigen::Isometry3d> body_b = gt.T_world_body.Interpolate(f.stamp_b);
    if (!body_a.ok() || !body_b.ok()) continue;
    const Eigen::Isometry3d T_world_a = *body_a * f.T_submap_scan_a.inverse();
    const Eigen::Isometry3d T_world_b = *body_b * f.T_submap_scan_b.inverse();
    const eval::RelativePoseError e =
        eval::RelativePoseErrorAgainstTruth(f.T_a_b, f.covariance, T_world_a, T_world_b);
    Json error = Json::array(), sigma = Json::array();
    for (int i = 0; i < 6; ++i) {
      error.push_back(e.error[i]);
      sigma.push_back(std::sqrt(std::max(0.0, f.covariance(i, i))));
    }
    out.push_back({{"kind", SubmapFactorKindName(f.kind)},
                   {"a", f.a},
                   {"b", f.b},
                   {"dt_s", f.stamp_b.SecondsSince(f.stamp_a)},
                   {"distance_m", (T_world_b.translation() - T_world_a.translation()).norm()},
                   {"error", error},
                   {"sigma", sigma},
                   {"chi2", Opt(e.chi2)}});
  }
  return out;
}

// The whole --config (with drive.*: the sweep runs the boresight self-calibration where
// drive.estimate_extrinsics is set, as slam_mms_run does).
StatusOr<app::RunConfig> BaseConfig(const fs::path& config) {
  app::RunConfig c;
  if (!config.empty()) SLAM_MMS_RETURN_IF_ERROR(app::ApplyConfigFile(config, &c));
  return c;
}

// The boresight self-calibration of drive.estimate_extrinsics, as slam_mms_run runs it: its
// report.json "extrinsics" (no file written) with "run_with_estimate", and *reader replaced by
// one with the estimate. A drive that cannot give it (FailedPrecondition: too few scans where the
// POS is good, as on an SPS drive's 4 m) runs with the file, as a calibration on by default
// would: {"status", "run_with_estimate": false}. Other errors are returned.
StatusOr<Json> SelfCalibrate(const MappingSystem::Options& options,
                             const ExtrinsicCalibrationOptions& calibration,
                             std::unique_ptr<DriveReader>* reader) {
  StatusOr<ExtrinsicCalibration> cal = CalibrateDriveExtrinsics(**reader, options, calibration);
  if (!cal.ok()) {
    if (cal.status().code() != StatusCode::kFailedPrecondition) return cal.status();
    return Json{{"status", cal.status().ToString()}, {"run_with_estimate", false}};
  }
  Json c = Json::parse(app::CalibrationJson(*cal, "", 0.0));
  c.erase("calibration_file");
  c["run_with_estimate"] = true;
  DriveExtrinsics estimated;
  estimated.T_body_lidar = cal->T_body_lidar_estimated;
  estimated.lidar_time_offset_s = cal->time_offset_s;
  *reader = OverrideExtrinsics(std::move(*reader), estimated);
  return c;
}

// The rotation from `truth` to `estimate` about the body axes, as a rotation vector [deg], and
// the lever-arm difference [m].
Json ExtrinsicErrorJson(const Eigen::Isometry3d& T_body_lidar_estimate,
                        const Eigen::Isometry3d& T_body_lidar_truth) {
  const Eigen::AngleAxisd aa(T_body_lidar_estimate.linear() *
                             T_body_lidar_truth.linear().transpose());
  const Eigen::Vector3d rot = aa.axis() * aa.angle() * (180.0 / M_PI);
  const Eigen::Vector3d xyz =
      T_body_lidar_estimate.translation() - T_body_lidar_truth.translation();
  return Json{{"rot_deg", {rot.x(), rot.y(), rot.z()}}, {"xyz_m", {xyz.x(), xyz.y(), xyz.z()}}};
}

}  // namespace

Json SpecToJson(const SweepRun& r, const RunSettings& s) {
  Json j{{"id", r.id},
         {"drive", r.drive},
         {"oxts_dir", r.oxts_dir.string()},
         {"oxts_start_s", r.oxts_start_s},
         {"duration_s", r.duration_s},
         {"seed", r.seed},
         {"scenario", GnssScenarioName(r.scenario)},
         {"outage", r.outage ? Json::array({r.outage->first, r.outage->second}) : Json(nullptr)},
         {"calib_error_rpy_deg",
          {r.calib_error_rpy_deg.x(), r.calib_error_rpy_deg.y(), r.calib_error_rpy_deg.z()}},
         {"calib_error_xyz_m",
          {r.calib_error_xyz_m.x(), r.calib_error_xyz_m.y(), r.calib_error_xyz_m.z()}},
         {"imu_mount_error_rpy_deg",
          {r.imu_mount_error_rpy_deg.x(), r.imu_mount_error_rpy_deg.y(),
           r.imu_mount_error_rpy_deg.z()}},
         {"motion",
          {{"path_m", r.motion.path_m},
           {"mean_speed_mps", r.motion.mean_speed_mps},
           {"start_speed_mps", r.motion.start_speed_mps},
           {"max_speed_mps", r.motion.max_speed_mps},
           {"stationary_fraction", r.motion.stationary_fraction},
           {"max_yaw_rate_dps", r.motion.max_yaw_rate_dps},
           {"total_turn_deg", r.motion.total_turn_deg},
           {"classes", r.motion.classes}}},
         {"modes", s.modes},
         {"config", s.config.string()},
         {"keep_drive", s.keep_drive},
         {"num_threads", s.num_threads}};
  return j;
}

Status SpecFromJson(const Json& j, SweepRun* r, RunSettings* s) {
  try {
    r->id = j.at("id").get<std::string>();
    r->drive = j.at("drive").get<std::string>();
    r->oxts_dir = j.at("oxts_dir").get<std::string>();
    r->oxts_start_s = j.at("oxts_start_s").get<double>();
    r->duration_s = j.at("duration_s").get<double>();
    r->seed = j.at("seed").get<uint64_t>();
    if (!ParseGnssScenario(j.at("scenario").get<std::string>(), &r->scenario)) {
      return InvalidArgumentError("spec: field scenario: unknown '" +
                                  j.at("scenario").get<std::string>() + "'");
    }
    r->outage.reset();
    if (!j.at("outage").is_null()) {
      r->outage =
          std::make_pair(j.at("outage").at(0).get<double>(), j.at("outage").at(1).get<double>());
    }
    // Absent in the specs of sweeps before session 40: the true calibration.
    r->calib_error_rpy_deg.setZero();
    r->calib_error_xyz_m.setZero();
    r->imu_mount_error_rpy_deg.setZero();
    if (j.contains("calib_error_rpy_deg")) {
      for (int i = 0; i < 3; ++i) {
        r->calib_error_rpy_deg(i) = j.at("calib_error_rpy_deg").at(i).get<double>();
        r->calib_error_xyz_m(i) = j.at("calib_error_xyz_m").at(i).get<double>();
        r->imu_mount_error_rpy_deg(i) = j.at("imu_mount_error_rpy_deg").at(i).get<double>();
      }
    }
    const Json& m = j.at("motion");
    r->motion.path_m = m.at("path_m").get<double>();
    r->motion.mean_speed_mps = m.at("mean_speed_mps").get<double>();
    r->motion.start_speed_mps = m.at("start_speed_mps").get<double>();
    r->motion.max_speed_mps = m.at("max_speed_mps").get<double>();
    r->motion.stationary_fraction = m.at("stationary_fraction").get<double>();
    r->motion.max_yaw_rate_dps = m.at("max_yaw_rate_dps").get<double>();
    r->motion.total_turn_deg = m.at("total_turn_deg").get<double>();
    r->motion.classes = m.at("classes").get<std::string>();
    s->modes = j.at("modes").get<std::vector<std::string>>();
    s->config = j.at("config").get<std::string>();
    s->keep_drive = j.at("keep_drive").get<bool>();
    s->num_threads = j.at("num_threads").get<int>();
  } catch (const Json::exception& e) {
    return InvalidArgumentError(std::string("spec: ") + e.what());
  }
  return OkStatus();
}

int RunOne(const fs::path& run_dir) {
  app::InstallLogSink();
  StatusOr<Json> spec_json = app::ReadJsonFile(run_dir / "spec.json");
  if (!spec_json.ok()) return Fail(run_dir, Json(), spec_json.status());
  SweepRun run;
  RunSettings settings;
  Status parsed = SpecFromJson(*spec_json, &run, &settings);
  if (!parsed.ok()) return Fail(run_dir, *spec_json, parsed);
  std::vector<MappingMode> modes;
  for (const std::string& name : settings.modes) {
    MappingMode mode;
    if (!ParseMappingMode(name, &mode)) {
      return Fail(run_dir, *spec_json, InvalidArgumentError("spec: unknown mode " + name));
    }
    modes.push_back(mode);
  }

  // The drive.
  sim::DriveSimulator::Options so;
  so.oxts_drive_dir = run.oxts_dir;
  so.oxts_start_s = run.oxts_start_s;
  so.duration_s = run.duration_s;
  so.seed = run.seed;
  so.write_scene_cloud = false;
  so.num_threads = settings.num_threads;
  so.calib_error_rpy_deg = run.calib_error_rpy_deg;
  so.calib_error_xyz_m = run.calib_error_xyz_m;
  so.imu_mount_error_rpy_deg = run.imu_mount_error_rpy_deg;
  ApplyScenario(run, &so);
  const auto t0 = std::chrono::steady_clock::now();
  StatusOr<sim::DriveSimulator> simulator = sim::DriveSimulator::Create(so);
  if (!simulator.ok()) return Fail(run_dir, *spec_json, simulator.status());
  const fs::path sim_dir = run_dir / "sim";
  StatusOr<sim::DriveSimulator::Summary> summary = simulator->Run(sim_dir);
  if (!summary.ok()) return Fail(run_dir, *spec_json, summary.status());
  const double sim_wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Json result{{"spec", *spec_json},
              {"sim",
               {{"scans", summary->num_scans},
                {"path_m", summary->path_length_m},
                {"fraction_fixed", summary->fraction_fixed},
                {"fraction_float", summary->fraction_float},
                {"fraction_sps", summary->fraction_sps},
                {"fraction_none", summary->fraction_none},
                {"wall_s", sim_wall}}}};

  // The methods, as slam_mms_run runs them.
  StatusOr<std::unique_ptr<DriveReader>> reader = OpenDrive(summary->drive_dir, {});
  if (!reader.ok()) return Fail(run_dir, *spec_json, reader.status());
  StatusOr<app::RunConfig> base = BaseConfig(settings.config);
  if (!base.ok()) return Fail(run_dir, *spec_json, base.status());
  MappingSystem::Options options = base->system;
  // The run's outage as slam_mms_run --gnss-outage gives it: to the self-calibration's POS too.
  std::vector<eval::OutageWindow> outages;
  if (run.outage) {
    options.gnss_outages.push_back(*run.outage);
    outages.push_back({run.outage->first, run.outage->second});
  }
  // The calibration file against the truth, and the self-calibration where the config asks.
  const Eigen::Isometry3d T_body_lidar_true = so.T_lidar_body.inverse();
  result["sim"]["calibration_file_error"] =
      ExtrinsicErrorJson((*reader)->streams().T_body_lidar, T_body_lidar_true);
  if (base->drive.estimate_extrinsics) {
    options.T_body_lidar = (*reader)->streams().T_body_lidar;
    StatusOr<Json> c = SelfCalibrate(options, base->drive.extrinsic_calibration, &*reader);
    if (!c.ok()) return Fail(run_dir, *spec_json, c.status());
    if (c->contains("T_body_lidar_estimated")) {
      (*c)["error"] = ExtrinsicErrorJson((*reader)->streams().T_body_lidar, T_body_lidar_true);
    }
    result["calibration"] = std::move(c).value();
  }
  options.T_body_lidar = (*reader)->streams().T_body_lidar;
  if ((*reader)->streams().t_body_antenna_m) {
    options.ins.gnss.t_body_antenna = *(*reader)->streams().t_body_antenna_m;
  }
  const Timestamp reference = (*reader)->ScanStart(0);
  Json methods = Json::object();
  std::optional<eval::GroundTruth> gt;
  std::optional<GeodeticPoint> origin;
  std::vector<RelativeFactorRecord> full_factors;
  Status export_status;
  for (const MappingMode mode : modes) {
    std::function<void(const MappingSystem&)> on_finished;
    if (mode == MappingMode::kFull) {
      on_finished = [&](const MappingSystem& system) {
        StatusOr<DriveResult> drive = system.ExportDriveResult();
        if (drive.ok()) {
          full_factors = RelativeFactors(*drive);
        } else {
          export_status = drive.status();
        }
      };
    }
    app::ModeRun mr = app::RunMode(mode, options, **reader, PosWorkflow::kForward, false, nullptr,
                                   {}, on_finished);
    if (!gt && mr.origin) {
      origin = *mr.origin;  // the frame gt is loaded in
      StatusOr<eval::GroundTruth> loaded =
          eval::LoadGroundTruth(summary->drive_dir, **reader, *mr.origin);
      if (!loaded.ok()) return Fail(run_dir, *spec_json, loaded.status());
      gt = std::move(loaded).value();
    }
    const app::MethodEvaluation ev = app::EvaluateMethod(
        mr, gt ? &*gt : nullptr, outages, mr.first_scan_start ? *mr.first_scan_start : reference,
        settings.num_threads);
    methods[mr.name] = MethodJson(mr, ev, gt ? &*gt : nullptr);
    if (mode == MappingMode::kFull && gt) {
      if (!export_status.ok()) return Fail(run_dir, *spec_json, export_status);
      methods[mr.name]["level2_factors"] = RelativeFactorsJson(full_factors, *gt);
    }
  }
  result["methods"] = methods;
  // The input's own error: the OXTS records' positions (the GNSS/INS solution the POS reads its
  // fixes from) against the truth over the scans' span, as the methods' ATE (rule full_bounded).
  if (gt && origin && (*reader)->NumScans() > 0) {
    StatusOr<eval::GroundTruth> records =
        eval::LoadOxtsGroundTruth(**reader, *origin, eval::OxtsPositions::kRecorded);
    if (!records.ok()) return Fail(run_dir, *spec_json, records.status());
    const Timestamp from = (*reader)->ScanStart(0);
    const Timestamp to = (*reader)->ScanEnd((*reader)->NumScans() - 1);
    Trajectory span;
    for (const StampedPose& p : records->T_world_body.poses()) {
      if (p.stamp < from || to < p.stamp) continue;
      const Status added = span.Add(p);
      if (!added.ok()) return Fail(run_dir, *spec_json, added);
    }
    StatusOr<eval::AteResult> ate = eval::ComputeAte(span, gt->T_world_body);
    if (!ate.ok()) return Fail(run_dir, *spec_json, ate.status());
    result["sim"]["records_ate_m"] = ate->ate_rmse_m;
  }
  if (!settings.keep_drive) {
    std::error_code ec;
    fs::remove_all(sim_dir, ec);
  }
  const Status written = app::WriteJsonFile(result, run_dir / "result.json", 2);
  if (!written.ok()) {
    std::fprintf(stderr, "slam_mms_sweep --run-one: %s\n", written.ToString().c_str());
    return 1;
  }
  return 0;
}

int RealOne(const fs::path& run_dir, const fs::path& drive_dir, const fs::path& config) {
  app::InstallLogSink();
  Json spec{{"drive", drive_dir.string()}, {"config", config.string()}};
  StatusOr<app::RunConfig> base = BaseConfig(config);
  if (!base.ok()) return Fail(run_dir, spec, base.status());
  // lidar_only on the frames read with KITTI's vertical-angle correction (as the peer reads
  // them: KISS-ICP corrects every KITTI scan by 0.205 deg) and as recorded; after the boresight
  // self-calibration where the config asks for it, as slam_mms_run does.
  Json result{{"spec", spec}};
  for (const double correction_deg : {kKittiVerticalCorrectionDeg, 0.0}) {
    DriveSourceOptions source;
    source.kitti_vertical_correction_deg = correction_deg;
    StatusOr<std::unique_ptr<DriveReader>> reader = OpenDrive(drive_dir, source);
    if (!reader.ok()) return Fail(run_dir, spec, reader.status());
    MappingSystem::Options options = base->system;
    options.T_body_lidar = (*reader)->streams().T_body_lidar;
    Json calibration;
    if (base->drive.estimate_extrinsics) {
      StatusOr<Json> c = SelfCalibrate(options, base->drive.extrinsic_calibration, &*reader);
      if (!c.ok()) return Fail(run_dir, spec, c.status());
      calibration = std::move(c).value();
      options.T_body_lidar = (*reader)->streams().T_body_lidar;
    }
    app::ModeRun mr =
        app::RunMode(MappingMode::kLidarOnly, options, **reader, PosWorkflow::kForward, false);
    if (!mr.status.ok()) return Fail(run_dir, spec, mr.status);
    if (!mr.origin) return Fail(run_dir, spec, FailedPreconditionError("lidar_only: no origin"));
    StatusOr<eval::GroundTruth> gt = eval::LoadGroundTruth(drive_dir, **reader, *mr.origin);
    if (!gt.ok()) return Fail(run_dir, spec, gt.status());
    eval::RelativeErrorOptions ro;
    ro.segment_lengths_m = {10, 20, 25, 30, 40, 50};
    StatusOr<eval::RelativeErrorResult> rel =
        eval::ComputeRelativeError(mr.trajectory, gt->T_world_body, ro);
    if (!rel.ok()) return Fail(run_dir, spec, rel.status());
    Json t = Json::object(), r = Json::object();
    for (const eval::SegmentLengthError& s : rel->per_length) {
      const std::string key = std::to_string(static_cast<int>(s.length_m));
      t[key] = s.num_segments > 0 ? Json(s.t_rel_pct) : Json(nullptr);
      r[key] = s.num_segments > 0 ? Json(s.r_rel_deg_per_100m) : Json(nullptr);
    }
    result[correction_deg != 0.0 ? "real" : "real_uncorrected"] = {
        {"drive", drive_dir.filename().string()},
        {"kitti_vertical_correction_deg", correction_deg},
        {"frames", mr.scans_processed},
        {"path_m", rel->ground_truth_path_length_m},
        {"t_rel_pct", rel->t_rel_pct},
        {"r_rel_deg_per_100m", rel->r_rel_deg_per_100m},
        {"t_rel_pct_by_length", t},
        {"r_rel_deg_per_100m_by_length", r},
        {"scans_per_s", mr.scans_per_s}};
    if (!calibration.is_null()) {
      result[correction_deg != 0.0 ? "real" : "real_uncorrected"]["calibration"] = calibration;
    }
  }
  const Status written = app::WriteJsonFile(result, run_dir / "result.json", 2);
  return written.ok() ? 0 : 1;
}

}  // namespace slam_mms::sweep
