// slam_mms_merge's entry point (the app and python -m slam_mms merge); see merge_main.hpp.
#include "slam_mms_merge/merge_main.hpp"

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/drive/open_drive.hpp"
#include "slam_mms/eval/ground_truth.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/eval/outage_error.hpp"
#include "slam_mms/eval/trajectory_error.hpp"
#include "slam_mms/io/georef.hpp"
#include "slam_mms/io/map_io.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms/merge/drive_adjustment.hpp"
#include "slam_mms/merge/drive_result_io.hpp"
#include "slam_mms/merge/union_map.hpp"
#include "slam_mms/version.hpp"

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace slam_mms::app {
namespace {

int Fail(const std::string& message) {
  std::fprintf(stderr, "slam_mms_merge: %s\n", message.c_str());
  return 1;
}

// T_world_body of every scan (DriveResult::ScanPoses: at the drive's submap poses, or at
// `submap_poses`).
Trajectory ScanTrajectory(const DriveResult& r,
                          const std::vector<Eigen::Isometry3d>* submap_poses = nullptr) {
  Trajectory t;
  for (const auto& [stamp, T] : r.ScanPoses(submap_poses)) {
    if (!t.Add(stamp, T).ok()) continue;  // a duplicate stamp (cannot happen in one drive)
  }
  return t;
}

// The drives' map clouds (read one at a time from their drive-result folders) at the given submap
// poses (per drive, per submap; null: the drives' own), voxel-downsampled.
StatusOr<PointCloud> UnionMap(const std::vector<DriveAdjustment::Drive>& drives,
                              const std::vector<std::string>& drive_dirs,
                              const std::vector<std::vector<Eigen::Isometry3d>>* poses,
                              double voxel_m) {
  std::vector<UnionMapSubmap> submaps;
  for (size_t d = 0; d < drives.size(); ++d) {
    const auto& subs = drives[d].result.submaps;
    for (size_t k = 0; k < subs.size(); ++k) {
      submaps.push_back({fs::path(drive_dirs[d]) / "drive_result", subs[k].id,
                         poses != nullptr ? (*poses)[d][k] : subs[k].T_world_submap});
    }
  }
  UnionMapOptions o;
  o.voxel_m = voxel_m;
  return DownsampledUnionMap(submaps, o);
}

std::optional<double> Entropy(const PointCloud& map, int threads) {
  eval::MapEntropyOptions o;
  o.num_threads = threads;
  auto r = eval::ComputeMapEntropy(map.View(), o);
  if (!r.ok() || !std::isfinite(r->mean_map_entropy)) return std::nullopt;
  return r->mean_map_entropy;
}

Json OptionalNumber(const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); }

struct DriveTruth {
  std::optional<eval::GroundTruth> gt;
  std::string why;  // where there is none
};

// The ground truth of the drive run into `out_dir` (its report.json's input.drive), in the world
// about `origin`.
DriveTruth LoadTruth(const fs::path& out_dir, const GeodeticPoint& origin) {
  DriveTruth t;
  std::ifstream in(out_dir / "report.json");
  if (!in) {
    t.why = "no " + (out_dir / "report.json").string();
    return t;
  }
  Json report = Json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (report.is_discarded() || !report.contains("input") || !report["input"].contains("drive") ||
      !report["input"]["drive"].is_string()) {
    t.why = (out_dir / "report.json").string() + " names no input.drive";
    return t;
  }
  // input.drive is as slam_mms_run was given it: a relative path is relative to where that ran,
  // tried here as is, then beside the output folder and inside it.
  fs::path drive = report["input"]["drive"].get<std::string>();
  if (drive.is_relative() && !fs::exists(drive)) {
    for (const fs::path& base : {out_dir.parent_path(), out_dir}) {
      if (fs::exists(base / drive)) {
        drive = base / drive;
        break;
      }
    }
  }
  auto reader = OpenDrive(drive, DriveSourceOptions());
  if (!reader.ok()) {
    t.why = reader.status().ToString();
    return t;
  }
  auto gt = eval::LoadGroundTruth(drive, **reader, origin);
  if (!gt.ok()) {
    t.why = gt.status().ToString();
    return t;
  }
  t.gt = std::move(gt).value();
  return t;
}

struct DriveErrors {
  std::optional<double> ate_m;
  std::optional<double> max_outage_err_m;
};

DriveErrors Errors(const Trajectory& estimate, const eval::GroundTruth& gt,
                   const std::vector<GnssAvailabilityInterval>& availability) {
  DriveErrors e;
  auto ate = eval::ComputeAte(estimate, gt.T_world_body);
  if (!ate.ok()) return e;
  e.ate_m = ate->ate_rmse_m;
  std::vector<eval::OutageWindow> windows;
  if (availability.empty()) return e;
  const Timestamp reference = availability.front().start;
  for (const GnssAvailabilityInterval& a : availability) {
    if (a.availability != GnssAvailability::kOutage) continue;
    eval::OutageWindow w;
    w.start_s = a.start.SecondsSince(reference);
    w.duration_s = a.end.SecondsSince(a.start);
    if (w.duration_s > 0.0) windows.push_back(w);
  }
  if (windows.empty()) return e;
  auto outage = eval::ComputeOutageErrors(ate->errors, windows, reference);
  if (outage.ok() && outage->num_poses > 0) e.max_outage_err_m = outage->max_pos_err_m;
  return e;
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int MergeMainImpl(int argc, const char* const* argv) {
  std::vector<std::string> drive_dirs;
  std::string out_dir, crs, log_level = "warning";
  double las_tile_size = 100.0;
  int threads = 2;
  DriveAdjustment::Options options;
  CLI::App app("slam_mms_merge: drives of one area adjusted into one map (docs/merge.md)",
               "slam_mms_merge");
  app.set_version_flag("--version", std::string("slam_mms_merge ") + SLAM_MMS_VERSION_STRING);
  app.add_option("--drive", drive_dirs, "a slam_mms_run --out folder run with --drive-result")
      ->required();
  app.add_option("--out", out_dir, "output folder (DIR/merged is written)")->required();
  app.add_option("--las-tile-size", las_tile_size, "LAS tile size of the merged map [m]")
      ->check(CLI::PositiveNumber);
  app.add_option("--crs", crs, "output CRS of the LAS tiles (default WGS 84 / UTM of the origin)");
  app.add_option("--threads", threads, "threads")->check(CLI::Range(1, 64));
  app.add_option("--gnss-bias-sigma", options.gnss_bias_sigma_m,
                 "prior sigma of each drive's GNSS datum offset [m]; 0 = one datum for all")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--overlap-sigma-floor-rad", options.registration_sigma_floor_rad,
                 "floor of an overlap factor's rotation sigma [rad] (default 0.001)")
      ->check(CLI::PositiveNumber);
  app.add_option("--overlap-sigma-floor-m", options.registration_sigma_floor_m,
                 "floor of an overlap factor's translation sigma [m] (default 0.02)")
      ->check(CLI::PositiveNumber);
  bool no_pose_priors = false;
  app.add_flag("--no-pose-priors", no_pose_priors, "leave the drives' attitude priors out");
  app.add_option("--overlap-distance", options.overlap_distance_m,
                 "submaps of two drives whose scans come this close are tested [m]")
      ->check(CLI::PositiveNumber);
  app.add_option("--variance-components", options.variance_component_rounds,
                 "rounds of variance component estimation: each drive's factors of one kind and "
                 "the overlaps scaled by their variance factor (default 10; 0 = off)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--variance-factor-min", options.variance_factor_min,
                 "lowest variance factor of the relative factors (reckon, registration, loops, "
                 "overlaps; default 1: what a drive states is only loosened)")
      ->check(CLI::Range(1e-6, 1.0));
  app.add_option("--log-level", log_level, "debug|info|warning|error");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // help and version: 0; a bad command line: 2
  }
  LogLevel level = LogLevel::kWarning;
  if (!ParseLogLevel(log_level, &level)) {
    Fail("--log-level " + log_level + ": expected debug, info, warning or error");
    return 2;  // a bad command line, as CLI11's own errors
  }
  SetLogSink(StderrLogSink());
  SetMinLogLevel(level);
  const auto t0 = std::chrono::steady_clock::now();

  // The output folder first: an unwritable one fails before any work.
  const fs::path merged = fs::path(out_dir) / "merged";
  std::error_code ec;
  fs::create_directories(merged, ec);
  {
    std::ofstream probe(merged / ".write_test");
    if (ec || !probe) return Fail("--out: cannot write into " + merged.string());
  }
  fs::remove(merged / ".write_test", ec);

  std::vector<DriveAdjustment::Drive> drives;
  std::map<std::string, int> names;
  for (const std::string& dir : drive_dirs) {
    DriveResultReadOptions read;
    read.map_clouds = false;  // read one at a time for the maps (UnionMap)
    auto r = ReadDriveResult(fs::path(dir) / "drive_result", read);
    if (!r.ok()) {
      return Fail("--drive " + dir + ": " + r.status().ToString() +
                  " (run slam_mms_run with --drive-result)");
    }
    std::string name = fs::path(dir).lexically_normal().filename().string();
    if (name.empty()) name = fs::path(dir).lexically_normal().parent_path().filename().string();
    if (names[name]++ > 0) name += "_" + std::to_string(names[name]);
    std::printf("drive %s: %zu submaps, %zu factors\n", name.c_str(), r->submaps.size(),
                r->factors.size());
    drives.push_back({name, std::move(r).value()});
  }

  options.num_threads = threads;
  options.use_pose_priors = !no_pose_priors;
  options.graph.num_threads = threads;
  auto adjusted = DriveAdjustment::Run(drives, options);
  if (!adjusted.ok()) return Fail(adjusted.status().ToString());
  const DriveAdjustment::Result& res = *adjusted;
  const double adjust_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // Trajectories and ground truth.
  Json drives_json = Json::array();
  std::vector<std::vector<Eigen::Isometry3d>> true_submap_poses;
  // Per drive, where it has ground truth: the true pose of each submap (by id).
  std::vector<std::map<SubmapId, Eigen::Isometry3d>> true_pose_of(res.drives.size());
  bool all_truth = true;
  for (size_t d = 0; d < res.drives.size(); ++d) {
    const Trajectory after_traj = ScanTrajectory(res.drives[d].result);
    const Trajectory before_traj =
        ScanTrajectory(res.drives[d].result, &res.T_world_submap_input[d]);
    Status s = WriteTrajectoryTum(after_traj, merged / (res.drives[d].name + ".tum"));
    if (s.ok()) s = WriteTrajectoryTum(before_traj, merged / (res.drives[d].name + "_before.tum"));
    if (!s.ok()) return Fail(s.ToString());
    Json j;
    j["name"] = res.drives[d].name;
    j["path"] = drive_dirs[d];
    j["submaps"] = res.drives[d].result.submaps.size();
    const Eigen::Vector3d b = res.gnss_bias_m[d];
    j["gnss_bias_m"] = {b.x(), b.y(), b.z()};
    DriveTruth truth = LoadTruth(drive_dirs[d], res.origin);
    if (truth.gt) {
      const DriveErrors eb = Errors(before_traj, *truth.gt, res.drives[d].result.gnss_availability);
      const DriveErrors ea = Errors(after_traj, *truth.gt, res.drives[d].result.gnss_availability);
      j["ate_before_m"] = OptionalNumber(eb.ate_m);
      j["ate_after_m"] = OptionalNumber(ea.ate_m);
      j["max_outage_err_before_m"] = OptionalNumber(eb.max_outage_err_m);
      j["max_outage_err_after_m"] = OptionalNumber(ea.max_outage_err_m);
      j["ground_truth"] = truth.gt->kind;
      std::vector<Eigen::Isometry3d> poses;
      for (const DriveSubmap& sub : res.drives[d].result.submaps) {
        auto T = truth.gt->T_world_body.Interpolate(sub.scans.front().stamp, 0.2);
        if (!T.ok()) all_truth = false;
        if (T.ok()) true_pose_of[d][sub.id] = *T;
        poses.push_back(T.ok() ? *T : sub.T_world_submap);
      }
      true_submap_poses.push_back(std::move(poses));
    } else {
      all_truth = false;
      j["ground_truth"] = nullptr;
      j["ground_truth_missing"] = truth.why;
      for (const char* k :
           {"ate_before_m", "ate_after_m", "max_outage_err_before_m", "max_outage_err_after_m"}) {
        j[k] = nullptr;
      }
    }
    drives_json.push_back(std::move(j));
  }

  // Overlaps: each registration T_a_b (translation, rotation vector in submap a's frame) and,
  // where both submaps have ground truth, its error against the true relative pose (translation in
  // the common world's E, N, U axes; rotation angle; chi2 against the stated covariance).
  std::vector<double> before, after;
  int verified = 0;
  std::ofstream csv(merged / "overlaps.csv");
  csv << "drive_a,submap_a,drive_b,submap_b,distance_m,verified,accepted,hypotheses_converged,"
         "inlier_ratio,rms_m,self_rms_m,offset_before_m,offset_after_m,x_m,y_m,z_m,rx_deg,ry_deg,"
         "rz_deg,truth_err_e_m,truth_err_n_m,truth_err_u_m,truth_err_deg,truth_chi2,verdict\n";
  constexpr double kDeg = 180.0 / M_PI;
  for (const auto& ov : res.overlaps) {
    verified += ov.verified ? 1 : 0;
    if (ov.accepted) {
      before.push_back(ov.offset_before_m);
      after.push_back(ov.offset_after_m);
    }
    csv << res.drives[ov.drive_a].name << "," << ov.submap_a << "," << res.drives[ov.drive_b].name
        << "," << ov.submap_b << "," << ov.distance_m << "," << ov.verified << "," << ov.accepted
        << "," << ov.hypotheses_converged << "," << ov.inlier_ratio << "," << ov.rms_m << ","
        << ov.self_rms_m << "," << ov.offset_before_m << "," << ov.offset_after_m;
    if (ov.verified) {
      const Eigen::Vector3d t = ov.T_a_b.translation(), r = kDeg * so3::Log(ov.T_a_b.linear());
      csv << "," << t.x() << "," << t.y() << "," << t.z() << "," << r.x() << "," << r.y() << ","
          << r.z();
    } else {
      csv << ",,,,,,";
    }
    const auto ta = true_pose_of[ov.drive_a].find(ov.submap_a);
    const auto tb = true_pose_of[ov.drive_b].find(ov.submap_b);
    if (ov.verified && ta != true_pose_of[ov.drive_a].end() &&
        tb != true_pose_of[ov.drive_b].end()) {
      const Eigen::Isometry3d T_true = ta->second.inverse() * tb->second;
      const Eigen::Vector3d e =
          ta->second.linear() * (ov.T_a_b.translation() - T_true.translation());
      // Rotation first, as the factor's covariance: its angle, and chi2 with 6 degrees of freedom.
      const eval::RelativePoseError re =
          eval::RelativePoseErrorAgainstTruth(ov.T_a_b, ov.covariance, ta->second, tb->second);
      csv << "," << e.x() << "," << e.y() << "," << e.z() << "," << kDeg * re.error.head<3>().norm()
          << "," << re.chi2;
    } else {
      csv << ",,,,,";
    }
    csv << ",\"" << ov.verdict << "\"\n";
  }
  csv.close();

  // Maps: merged, the union of the drives' own maps, the union at the true poses.
  const double voxel = 0.1;
  // One map at a time in memory (each the output of DownsampledUnionMap).
  std::optional<double> e_before, e_true;
  {
    auto before_map = UnionMap(res.drives, drive_dirs, &res.T_world_submap_input, voxel);
    if (!before_map.ok()) return Fail(before_map.status().ToString());
    e_before = Entropy(*before_map, threads);
  }
  if (all_truth) {
    auto true_map = UnionMap(res.drives, drive_dirs, &true_submap_poses, voxel);
    if (!true_map.ok()) return Fail(true_map.status().ToString());
    e_true = Entropy(*true_map, threads);
  }
  auto merged_or = UnionMap(res.drives, drive_dirs, nullptr, voxel);
  if (!merged_or.ok()) return Fail(merged_or.status().ToString());
  const PointCloud& merged_map = *merged_or;
  const std::optional<double> e_merged = Entropy(merged_map, threads);
  auto geo = GeoReference::Create(res.origin, crs);
  if (!geo.ok()) return Fail("--crs: " + geo.status().ToString());
  MapCloud map;
  map.cloud = std::move(merged_or).value();
  auto tiles = WriteLasTiles(map, *geo, merged / "map", las_tile_size, LasWriteOptions());
  if (!tiles.ok()) return Fail(tiles.status().ToString());

  Json report;
  report["version"] = SLAM_MMS_VERSION_STRING;
  std::vector<std::string> cmd(argv, argv + argc);
  report["command_line"] = cmd;
  report["origin"] = {{"latitude_deg", res.origin.latitude_deg},
                      {"longitude_deg", res.origin.longitude_deg},
                      {"height_m", res.origin.height_m}};
  report["crs"] = {{"name", geo->crs_name()}, {"epsg", geo->epsg()}};
  report["drives"] = std::move(drives_json);
  report["overlaps"] = {{"tested", res.overlaps.size()},
                        {"verified", verified},
                        {"accepted", res.num_accepted()},
                        {"rejection_rounds", res.rejection_rounds}};
  report["overlap_offset_m"] = {
      {"before", Median(before)},
      {"after", Median(after)},
      {"before_max", before.empty() ? 0.0 : *std::max_element(before.begin(), before.end())},
      {"after_max", after.empty() ? 0.0 : *std::max_element(after.begin(), after.end())},
      {"statistic", "median over accepted overlaps"}};
  report["map_entropy"] = {{"merged", OptionalNumber(e_merged)},
                           {"union_before", OptionalNumber(e_before)},
                           {"union_true_poses", OptionalNumber(e_true)},
                           {"voxel_m", voxel}};
  report["solve"] = {{"usable", res.summary.usable()},
                     {"iterations", res.summary.iterations},
                     {"termination", SolveTerminationName(res.summary.termination)}};
  Json components = Json::array();
  for (const DriveAdjustment::VarianceComponent& c : res.variance_components) {
    components.push_back({{"drive", c.drive.empty() ? Json(nullptr) : Json(c.drive)},
                          {"kind", SubmapFactorKindName(c.kind)},
                          {"factors", c.factors},
                          {"redundancy", c.redundancy},
                          {"estimated", c.estimated},
                          {"variance_factor", c.variance_factor}});
  }
  report["variance_components"] = {
      {"rounds", res.variance_component_rounds},
      {"skipped", res.variance_components_skipped.empty() ? Json(nullptr)
                                                          : Json(res.variance_components_skipped)},
      {"groups", std::move(components)}};
  report["map_points"] = map.cloud.size();
  report["las_tiles"] = tiles->size();
  report["adjust_wall_s"] = adjust_s;
  report["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ofstream(merged / "report.json") << report.dump(2) << "\n";
  Status g = WriteGeorefJson(*geo, merged / "georef.json");
  if (!g.ok()) return Fail(g.ToString());

  std::printf(
      "overlaps: %zu tested, %d verified, %d accepted; offset where they overlap "
      "(median) %.3f m before, %.3f m after\n",
      res.overlaps.size(), verified, res.num_accepted(), Median(before), Median(after));
  auto fmt = [](const std::optional<double>& v) {
    return v ? std::to_string(*v) : std::string("-");
  };
  std::printf("map entropy: merged %s, union before %s, union at true poses %s\n",
              fmt(e_merged).c_str(), fmt(e_before).c_str(), fmt(e_true).c_str());
  for (const auto& j : report["drives"]) {
    auto num = [&](const char* k) {
      return j[k].is_null() ? std::string("-") : std::to_string(j[k].get<double>());
    };
    std::printf("drive %s: ATE %s -> %s m, max outage error %s -> %s m\n",
                j["name"].get<std::string>().c_str(), num("ate_before_m").c_str(),
                num("ate_after_m").c_str(), num("max_outage_err_before_m").c_str(),
                num("max_outage_err_after_m").c_str());
  }
  std::printf("outputs in %s\n", merged.string().c_str());
  return 0;
}

}  // namespace

int MergeMain(int argc, const char* const* argv) {
  // The log sink and level are set per run and the caller's put back (python -m slam_mms merge).
  LogSink previous = SetLogSink(nullptr);
  SetLogSink(previous);
  const LogLevel previous_level = MinLogLevel();
  const int code = MergeMainImpl(argc, argv);
  SetLogSink(previous);
  SetMinLogLevel(previous_level);
  return code;
}

}  // namespace slam_mms::app
