// slam_mms_sim_realism: is the simulator as hard as real data? (issue 16, the realism report)
//
//   slam_mms_sim_realism --real KITTI_RAW_DRIVE_DIR --out DIR [--seed N] [--threads N]
//                        [--sim SIMULATED_DRIVE_DIR] [--extrinsics FILE] [--config FILE]
//                        [--scan-stride N] [--no-lidar-only]
//
// Simulates the real drive's motion (its OXTS, the same scan times) with the default simulator
// (or takes an already simulated copy, --sim, written by slam_mms_sim with any options), then
// measures both drives the same way and writes them side by side:
//   - scan statistics (eval::ScanStatistics: points per scan, range / intensity / per-ring /
//     planarity / normal histograms, range-image fill, geometric class shares, mixed pixels);
//   - odometry difficulty: ICP-only frame-to-frame point-to-plane (RunIcpOdometry) and the
//     library's lidar_only mode, relative errors (eval) of the real drive against its OXTS and of
//     the simulated one against its ground truth, and their ratio sim / real;
//   - the mean map entropy of a map built from the ground-truth poses (OXTS for the real drive,
//     the truth for the simulated one), scans de-skewed with those poses, the same options.
// Outputs: DIR/report.json, DIR/report.md, DIR/scan_statistics.png (histograms),
// DIR/scans.png (a real and a simulated scan: top view, range image, perspective), DIR/sim/ (the
// simulated copy, when simulated here). --extrinsics replaces the real drive's calibration (e.g.
// the boresight slam_mms_run --calibrate-extrinsics estimated): KITTI's factory calibration is off
// by about 1.7 deg in yaw against the OXTS attitude on drive 0013 (docs/calibration.md), which
// alone costs about 3 % of t_rel on short segments.
// Exit status: 0 done, 1 a failure (message on stderr), 2 a bad command line.
#include <CLI/CLI.hpp>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/core/voxel_downsample.hpp"
#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/drive/icp_odometry.hpp"
#include "slam_mms/drive/open_drive.hpp"
#include "slam_mms/eval/ground_truth.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/eval/oxts_reference.hpp"
#include "slam_mms/eval/relative_error.hpp"
#include "slam_mms/eval/scan_statistics.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms/sim/scan_renderer.hpp"
#include "slam_mms/version.hpp"
#include "slam_mms_run/config_file.hpp"

namespace fs = std::filesystem;
using namespace slam_mms;
using nlohmann::json;

namespace {

struct Args {
  fs::path real, sim, out, extrinsics, config;
  uint64_t seed = 1;
  int threads = 2;
  int scan_stride = 1;
  bool lidar_only = true;
};

struct DriveMeasures {
  std::string label;
  fs::path dir;
  size_t scans = 0;
  double path_m = 0.0;
  eval::ScanStatistics stats;
  std::optional<eval::RelativeErrorResult> icp, lidar_only;  // against the ground truth
  // Against the drive's OXTS records (for the real drive the ground truth itself), with recorded
  // and with velocity-integrated positions (eval/oxts_reference.hpp), and how the two agree.
  std::optional<eval::RelativeErrorResult> icp_oxts, lidar_only_oxts;
  std::optional<eval::RelativeErrorResult> icp_oxts_velocity, lidar_only_oxts_velocity;
  std::vector<std::pair<std::string, eval::IncrementAgreement>> increments;
  size_t icp_unusable = 0;
  double icp_rms_m = 0.0;
  std::optional<eval::MapEntropyResult> gt_map;
  std::string ground_truth_kind;
  PointCloud sample_scan;
};

int Fail(const Status& s) {
  std::cerr << "slam_mms_sim_realism: " << s.ToString() << "\n";
  return 1;
}

void Progress(const std::string& line) {
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

// The devkit's 100..800 m where the drive is long enough, else 10..80 m, as slam_mms_run.
eval::RelativeErrorOptions SegmentsFor(double path_m) {
  return path_m >= 400.0 ? eval::RelativeErrorOptions::Kitti()
                         : eval::RelativeErrorOptions::ShortDrive();
}

// A map from the ground-truth poses: every scan de-skewed point by point with the truth,
// reduced to 0.1 m voxels, then the mean map entropy (default options: r 0.5 m, voxel 0.1 m).
StatusOr<eval::MapEntropyResult> GroundTruthMapEntropy(const DriveReader& reader,
                                                       const Trajectory& T_world_body, int stride,
                                                       int threads) {
  const Eigen::Isometry3d T_body_lidar = reader.streams().T_body_lidar;
  PointCloud map;
  for (size_t k = 0; k < reader.NumScans(); k += static_cast<size_t>(stride)) {
    SLAM_MMS_ASSIGN_OR_RETURN(const Scan scan, reader.ReadScan(k));
    PointCloud world;
    world.reserve(scan.cloud.size());
    const std::vector<Eigen::Vector3f>& pts = scan.cloud.points();
    const std::vector<float>& dt = scan.cloud.time_offsets_s();
    // Poses at 1 ms steps across the sweep (interpolated), not one per point.
    std::vector<std::optional<Eigen::Isometry3d>> steps;
    const double duration = std::max(scan.DurationSeconds(), 0.0);
    const int n_steps = static_cast<int>(std::ceil(duration / 1e-3)) + 1;
    for (int s = 0; s <= n_steps; ++s) {
      const Timestamp t = scan.stamp_start.PlusSeconds(s * 1e-3);
      StatusOr<Eigen::Isometry3d> T = T_world_body.Interpolate(t, 0.06);
      steps.push_back(T.ok() ? std::optional<Eigen::Isometry3d>(*T * T_body_lidar) : std::nullopt);
    }
    for (size_t i = 0; i < pts.size(); ++i) {
      if (!pts[i].allFinite()) continue;
      const int s = std::clamp(static_cast<int>(std::lround((i < dt.size() ? dt[i] : 0.0f) / 1e-3)),
                               0, n_steps);
      if (!steps[static_cast<size_t>(s)]) continue;
      world.Add((*steps[static_cast<size_t>(s)] * pts[i].cast<double>()).cast<float>());
    }
    SLAM_MMS_ASSIGN_OR_RETURN(PointCloud reduced, VoxelDownsample(world, 0.1));
    for (const Eigen::Vector3f& p : reduced.points()) map.Add(p);
  }
  eval::MapEntropyOptions mo;
  mo.num_threads = threads;
  return eval::ComputeMapEntropy(map, mo);
}

StatusOr<DriveMeasures> Measure(const std::string& label, const fs::path& dir,
                                const fs::path& extrinsics, const MappingSystem::Options& base,
                                const Args& args) {
  DriveMeasures m;
  m.label = label;
  m.dir = dir;
  DriveSourceOptions so;
  so.kind = DriveSourceKind::kKittiRaw;
  so.extrinsics = extrinsics;
  SLAM_MMS_ASSIGN_OR_RETURN(std::unique_ptr<DriveReader> reader, OpenDrive(dir, so));
  m.scans = reader->NumScans();

  Progress(label + ": scan statistics over " + std::to_string(m.scans) + " scans");
  const eval::ScanStatisticsOptions so_stats;
  m.stats = eval::MakeScanStatistics(so_stats);
  for (size_t k = 0; k < reader->NumScans(); k += static_cast<size_t>(args.scan_stride)) {
    SLAM_MMS_ASSIGN_OR_RETURN(const Scan scan, reader->ReadScan(k));
    SLAM_MMS_ASSIGN_OR_RETURN(const eval::ScanStatistics s,
                              eval::ComputeScanStatistics(scan.cloud, so_stats));
    SLAM_MMS_RETURN_IF_ERROR(m.stats.Add(s));
    if (k == (reader->NumScans() / 2) / static_cast<size_t>(args.scan_stride) *
                 static_cast<size_t>(args.scan_stride)) {
      m.sample_scan = scan.cloud;
    }
  }

  // The lidar_only run first: its world origin is the one the ground truth is expressed in.
  std::optional<GeodeticPoint> origin;
  Trajectory lidar_only;
  if (args.lidar_only) {
    Progress(label + ": lidar_only");
    MappingSystem::Options o = base;
    o.mode = MappingMode::kLidarOnly;
    o.num_threads = args.threads;
    o.T_body_lidar = reader->streams().T_body_lidar;  // as slam_mms_run does
    if (reader->streams().t_body_antenna_m) {
      o.ins.gnss.t_body_antenna = *reader->streams().t_body_antenna_m;
    }
    DriveRun run = RunDrive(*reader, o);
    if (!run.status.ok()) return run.status.WithContext(label + ": lidar_only");
    origin = run.origin;
    lidar_only = run.trajectory;
  }
  if (!origin) {
    const DriveStreams& st = reader->streams();
    if (!st.pos.empty()) {
      origin = GeodeticPoint{st.pos.front().latitude_deg, st.pos.front().longitude_deg,
                             st.pos.front().height_m};
    } else if (!st.gnss.empty()) {
      origin = GeodeticPoint{st.gnss.front().latitude_deg, st.gnss.front().longitude_deg,
                             st.gnss.front().height_m};
    } else {
      return FailedPreconditionError(label + ": no POS or GNSS record to place the ground truth");
    }
  }
  SLAM_MMS_ASSIGN_OR_RETURN(const eval::GroundTruth gt,
                            eval::LoadGroundTruth(dir, *reader, *origin));
  m.ground_truth_kind = gt.kind;
  m.path_m = 0.0;
  {
    // Path length over the scans' span.
    const Timestamp t0 = reader->ScanStart(0), t1 = reader->ScanStart(reader->NumScans() - 1);
    std::optional<Eigen::Vector3d> last;
    for (const StampedPose& p : gt.T_world_body.poses()) {
      if (p.stamp < t0 || t1 < p.stamp) continue;
      if (last) m.path_m += (p.T_world_body.translation() - *last).norm();
      last = p.T_world_body.translation();
    }
  }
  const eval::RelativeErrorOptions segments = SegmentsFor(m.path_m);
  if (args.lidar_only) {
    StatusOr<eval::RelativeErrorResult> r =
        eval::ComputeRelativeError(lidar_only, gt.T_world_body, segments);
    if (!r.ok()) return r.status().WithContext(label + ": lidar_only relative error");
    m.lidar_only = *r;
  }

  Progress(label + ": ICP-only odometry");
  IcpOdometryOptions io;
  io.num_threads = args.threads;
  // Started at the reference pose (relative errors do not depend on it; the increments in the
  // world frame do): KITTI's first OXTS record comes up to a scan period after the first scan's
  // start, whose pose is then the first record's.
  StatusOr<Eigen::Isometry3d> first = gt.T_world_body.Interpolate(reader->ScanStart(0), 0.15);
  if (first.ok()) io.T_world_body_first = *first;
  SLAM_MMS_ASSIGN_OR_RETURN(const IcpOdometryResult icp, RunIcpOdometry(*reader, io));
  m.icp_unusable = icp.scans_unusable;
  SLAM_MMS_RETURN_IF_ERROR(
      WriteTrajectoryTum(icp.T_world_body, args.out / (label + "_icp_only.tum")));
  SLAM_MMS_RETURN_IF_ERROR(
      WriteTrajectoryTum(gt.T_world_body, args.out / (label + "_ground_truth.tum")));
  if (args.lidar_only) {
    SLAM_MMS_RETURN_IF_ERROR(
        WriteTrajectoryTum(lidar_only, args.out / (label + "_lidar_only.tum")));
  }
  m.icp_rms_m = icp.mean_rms_residual_m;
  {
    StatusOr<eval::RelativeErrorResult> r =
        eval::ComputeRelativeError(icp.T_world_body, gt.T_world_body, segments);
    if (!r.ok()) return r.status().WithContext(label + ": ICP-only relative error");
    m.icp = *r;
  }

  // The same odometry against the drive's OXTS, its recorded positions and its velocities
  // integrated: like for like between the real drive and the copy (whose OXTS carries the
  // simulated GNSS/INS errors); and how each track's increments over 1 s agree with the
  // integrated velocities (the OXTS's own positions first).
  SLAM_MMS_ASSIGN_OR_RETURN(
      const eval::GroundTruth oxts,
      eval::LoadOxtsGroundTruth(*reader, *origin, eval::OxtsPositions::kRecorded));
  SLAM_MMS_ASSIGN_OR_RETURN(
      const eval::GroundTruth oxts_velocity,
      eval::LoadOxtsGroundTruth(*reader, *origin, eval::OxtsPositions::kVelocityIntegrated));
  SLAM_MMS_RETURN_IF_ERROR(
      WriteTrajectoryTum(oxts_velocity.T_world_body, args.out / (label + "_oxts_velocity.tum")));
  auto relative = [&](const Trajectory& est, const eval::GroundTruth& ref, const char* method,
                      std::optional<eval::RelativeErrorResult>* out) -> Status {
    StatusOr<eval::RelativeErrorResult> r =
        eval::ComputeRelativeError(est, ref.T_world_body, segments);
    if (!r.ok()) return r.status().WithContext(label + ": " + method + " against " + ref.kind);
    *out = *r;
    return OkStatus();
  };
  SLAM_MMS_RETURN_IF_ERROR(relative(icp.T_world_body, oxts, "ICP-only", &m.icp_oxts));
  SLAM_MMS_RETURN_IF_ERROR(
      relative(icp.T_world_body, oxts_velocity, "ICP-only", &m.icp_oxts_velocity));
  if (args.lidar_only) {
    SLAM_MMS_RETURN_IF_ERROR(relative(lidar_only, oxts, "lidar_only", &m.lidar_only_oxts));
    SLAM_MMS_RETURN_IF_ERROR(
        relative(lidar_only, oxts_velocity, "lidar_only", &m.lidar_only_oxts_velocity));
  }
  std::vector<std::pair<std::string, const Trajectory*>> tracks = {
      {"OXTS positions", &oxts.T_world_body}, {"ICP-only", &icp.T_world_body}};
  if (args.lidar_only) tracks.emplace_back("lidar_only", &lidar_only);
  for (const auto& [name, track] : tracks) {
    StatusOr<eval::IncrementAgreement> a =
        eval::CompareIncrements(*track, oxts_velocity.T_world_body, 1.0, 5.0);
    if (a.ok()) m.increments.emplace_back(name, *a);  // none on a drive that stands or crawls
  }
  if (args.lidar_only) {
    // The two odometries against each other: what they share is not the reference's.
    StatusOr<eval::IncrementAgreement> a =
        eval::CompareIncrements(icp.T_world_body, lidar_only, 1.0, 5.0);
    if (a.ok()) m.increments.emplace_back("ICP-only against lidar_only", *a);
  }

  Progress(label + ": map entropy from the ground-truth poses");
  SLAM_MMS_ASSIGN_OR_RETURN(m.gt_map,
                            GroundTruthMapEntropy(*reader, gt.T_world_body, 1, args.threads));
  return m;
}

json RelJson(const std::optional<eval::RelativeErrorResult>& r) {
  if (!r) return nullptr;
  json per = json::array();
  for (const eval::SegmentLengthError& s : r->per_length) {
    per.push_back({{"length_m", s.length_m},
                   {"segments", s.num_segments},
                   {"t_rel_pct", s.t_rel_pct},
                   {"r_rel_deg_per_100m", s.r_rel_deg_per_100m}});
  }
  return {{"segments", r->lengths_label},
          {"num_segments", r->num_segments},
          {"t_rel_pct", r->t_rel_pct},
          {"r_rel_deg_per_100m", r->r_rel_deg_per_100m},
          {"per_length", per}};
}

// sim / real and whether it lies within [1/1.5, 1.5] (issue 16's target).
json RatioJson(double real, double sim) {
  if (!(real > 0.0)) return nullptr;
  const double ratio = sim / real;
  return {{"real", real},
          {"sim", sim},
          {"ratio", ratio},
          {"within_1_5x", ratio >= 1.0 / 1.5 && ratio <= 1.5}};
}

std::string Fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof(b), f, v);
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  CLI::App app{"slam_mms_sim_realism: a real drive and its simulated copy measured side by side"};
  app.add_option("--real", args.real, "KITTI raw drive folder (<date>_drive_<n>_sync)")->required();
  app.add_option("--out", args.out, "output folder")->required();
  app.add_option("--sim", args.sim,
                 "an already simulated copy of the drive (default: simulate it into OUT/sim)");
  app.add_option("--seed", args.seed, "simulator seed (default 1)");
  app.add_option("--threads", args.threads, "threads (default 2)")->check(CLI::Range(1, 64));
  app.add_option("--extrinsics", args.extrinsics,
                 "calibration for the REAL drive (YAML or calib_imu_to_velo.txt)");
  app.add_option("--config", args.config, "slam_mms_run config file for lidar_only");
  app.add_option("--scan-stride", args.scan_stride, "scan statistics of every n-th scan (1)")
      ->check(CLI::Range(1, 1000));
  bool no_lidar_only = false;
  app.add_flag("--no-lidar-only", no_lidar_only, "skip the lidar_only runs");
  app.set_version_flag("--version", std::string(SLAM_MMS_VERSION_STRING));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  args.lidar_only = !no_lidar_only;
  SetLogSink(StderrLogSink());
  SetMinLogLevel(LogLevel::kWarning);

  MappingSystem::Options base;
  if (!args.config.empty()) {
    const Status s = app::ApplyConfigFile(args.config, &base);
    if (!s.ok()) {
      std::cerr << "slam_mms_sim_realism: " << s.ToString() << "\n";
      return 2;
    }
  }
  std::error_code ec;
  fs::create_directories(args.out, ec);
  if (ec) return Fail(NotFoundError("cannot create " + args.out.string() + ": " + ec.message()));

  // The simulated copy: the real drive's OXTS motion and scan times, the default simulator.
  fs::path sim_dir = args.sim;
  if (sim_dir.empty()) {
    sim::DriveSimulator::Options so;
    so.oxts_drive_dir = args.real;
    so.seed = args.seed;
    so.lead_in_s = 0.0;
    so.duration_s = 0.0;
    so.write_scene_cloud = false;
    so.num_threads = args.threads;
    StatusOr<sim::DriveSimulator> simulator = sim::DriveSimulator::Create(so);
    if (!simulator.ok()) return Fail(simulator.status().WithContext("simulator"));
    Progress("simulating the real drive's motion into " + (args.out / "sim").string());
    StatusOr<sim::DriveSimulator::Summary> summary = simulator->Run(args.out / "sim");
    if (!summary.ok()) return Fail(summary.status().WithContext("simulator"));
    sim_dir = summary->drive_dir;
  }

  StatusOr<DriveMeasures> real = Measure("real", args.real, args.extrinsics, base, args);
  if (!real.ok()) return Fail(real.status());
  StatusOr<DriveMeasures> simulated = Measure("sim", sim_dir, {}, base, args);
  if (!simulated.ok()) return Fail(simulated.status());

  const std::vector<eval::StatisticComparison> stats =
      eval::CompareScanStatistics(real->stats, simulated->stats, 0.2);
  {
    const Status s = eval::PlotScanStatistics(real->stats, simulated->stats, "real", "simulated",
                                              args.out / "scan_statistics.png");
    if (!s.ok()) return Fail(s);
    sim::ScanRenderer::LabeledScan a{"real (" + args.real.filename().string() + ")",
                                     &real->sample_scan};
    sim::ScanRenderer::LabeledScan b{"simulated copy", &simulated->sample_scan};
    const Status r = sim::ScanRenderer::WriteScanComparison({a, b}, args.out / "scans.png");
    if (!r.ok()) return Fail(r);
  }

  json report;
  report["real"] = {{"drive", args.real.string()},
                    {"scans", real->scans},
                    {"path_m", real->path_m},
                    {"ground_truth", real->ground_truth_kind},
                    {"extrinsics", args.extrinsics.string()}};
  report["sim"] = {{"drive", sim_dir.string()},
                   {"scans", simulated->scans},
                   {"path_m", simulated->path_m},
                   {"ground_truth", simulated->ground_truth_kind},
                   {"seed", args.seed}};
  json st = json::array();
  size_t stats_met = 0;
  for (const eval::StatisticComparison& c : stats) {
    st.push_back({{"name", c.name},
                  {"kind", c.is_histogram ? "histogram" : "scalar"},
                  {"real", c.real},
                  {"sim", c.sim},
                  {c.is_histogram ? "distance" : "ratio", c.value},
                  {"met", c.met}});
    stats_met += c.met ? 1 : 0;
  }
  report["scan_statistics"] = st;
  report["scan_statistics_met"] = {{"met", stats_met}, {"of", stats.size()}};
  json od;
  auto pair_json = [](const std::optional<eval::RelativeErrorResult>& r,
                      const std::optional<eval::RelativeErrorResult>& s) -> json {
    if (!r || !s) return nullptr;
    return {{"real", RelJson(r)},
            {"sim", RelJson(s)},
            {"t_rel", RatioJson(r->t_rel_pct, s->t_rel_pct)},
            {"r_rel", RatioJson(r->r_rel_deg_per_100m, s->r_rel_deg_per_100m)}};
  };
  od["against_oxts"] = {
      {"icp_only", pair_json(real->icp_oxts, simulated->icp_oxts)},
      {"lidar_only", pair_json(real->lidar_only_oxts, simulated->lidar_only_oxts)}};
  od["against_oxts_velocity"] = {
      {"icp_only", pair_json(real->icp_oxts_velocity, simulated->icp_oxts_velocity)},
      {"lidar_only",
       pair_json(real->lidar_only_oxts_velocity, simulated->lidar_only_oxts_velocity)}};
  od["icp_only"] = {
      {"real", RelJson(real->icp)},
      {"sim", RelJson(simulated->icp)},
      {"t_rel", RatioJson(real->icp->t_rel_pct, simulated->icp->t_rel_pct)},
      {"r_rel", RatioJson(real->icp->r_rel_deg_per_100m, simulated->icp->r_rel_deg_per_100m)},
      {"unusable_registrations", {real->icp_unusable, simulated->icp_unusable}},
      {"mean_rms_residual_m", {real->icp_rms_m, simulated->icp_rms_m}}};
  if (real->lidar_only && simulated->lidar_only) {
    od["lidar_only"] = {
        {"real", RelJson(real->lidar_only)},
        {"sim", RelJson(simulated->lidar_only)},
        {"t_rel", RatioJson(real->lidar_only->t_rel_pct, simulated->lidar_only->t_rel_pct)},
        {"r_rel", RatioJson(real->lidar_only->r_rel_deg_per_100m,
                            simulated->lidar_only->r_rel_deg_per_100m)}};
  }
  report["odometry"] = od;
  auto agreement_json = [](const eval::IncrementAgreement& a) -> json {
    return {{"window_s", a.window_s},
            {"windows", a.windows},
            {"mean_distance_m", a.mean_distance_m},
            {"rms_pct", a.rms_pct},
            {"along_mean_pct", a.along_mean_pct},
            {"along_std_pct", a.along_std_pct},
            {"cross_mean_pct", a.cross_mean_pct},
            {"cross_std_pct", a.cross_std_pct},
            {"vertical_rms_pct", a.vertical_rms_pct}};
  };
  json inc;
  for (const DriveMeasures* d : {&*real, &*simulated}) {
    inc[d->label] = json::object();
    for (const auto& [name, a] : d->increments) inc[d->label][name] = agreement_json(a);
  }
  report["increments_vs_oxts_velocity"] = inc;
  report["ground_truth_map_entropy"] = {
      {"real", real->gt_map->mean_map_entropy},
      {"sim", simulated->gt_map->mean_map_entropy},
      {"difference", simulated->gt_map->mean_map_entropy - real->gt_map->mean_map_entropy},
      {"radius_m", real->gt_map->options.radius_m},
      {"voxel_m", real->gt_map->options.voxel_size_m}};
  {
    std::ofstream f(args.out / "report.json");
    f << report.dump(2) << "\n";
    if (!f) return Fail(DataLossError("cannot write " + (args.out / "report.json").string()));
  }

  std::ostringstream md;
  md << "# Realism: " << args.real.filename().string() << " (real) vs its simulated copy\n\n";
  md << "Real: " << real->scans << " scans, " << Fmt("%.1f", real->path_m) << " m, against "
     << real->ground_truth_kind
     << (args.extrinsics.empty() ? "" : ", extrinsics " + args.extrinsics.string())
     << ". Simulated: " << simulated->scans << " scans, " << Fmt("%.1f", simulated->path_m)
     << " m, seed " << args.seed << ".\n\n";
  md << "## Odometry difficulty (sim / real within 1.5x either way)\n\n";
  md << "| method | real t_rel [%] | sim t_rel [%] | ratio | real r_rel [deg/100 m] | sim r_rel "
        "| ratio |\n|---|---|---|---|---|---|---|\n";
  auto row = [&](const std::string& name, const std::optional<eval::RelativeErrorResult>& r,
                 const std::optional<eval::RelativeErrorResult>& s) {
    if (!r || !s) return;
    md << "| " << name << " (" << r->lengths_label << ") | " << Fmt("%.3f", r->t_rel_pct) << " | "
       << Fmt("%.3f", s->t_rel_pct) << " | "
       << Fmt("%.2f", r->t_rel_pct > 0 ? s->t_rel_pct / r->t_rel_pct : 0.0) << " | "
       << Fmt("%.3f", r->r_rel_deg_per_100m) << " | " << Fmt("%.3f", s->r_rel_deg_per_100m) << " | "
       << Fmt("%.2f",
              r->r_rel_deg_per_100m > 0 ? s->r_rel_deg_per_100m / r->r_rel_deg_per_100m : 0.0)
       << " |\n";
  };
  row("ICP-only", real->icp, simulated->icp);
  row("lidar_only", real->lidar_only, simulated->lidar_only);
  md << "\nLike for like, both drives against their own OXTS records (the copy's carry its "
        "simulated GNSS/INS errors), with recorded positions and with the positions integrated "
        "from the records' velocities:\n\n| method, reference | real t_rel [%] | sim t_rel [%] | "
        "ratio | real r_rel [deg/100 m] | sim r_rel | ratio |\n|---|---|---|---|---|---|---|\n";
  row("ICP-only, OXTS positions", real->icp_oxts, simulated->icp_oxts);
  row("lidar_only, OXTS positions", real->lidar_only_oxts, simulated->lidar_only_oxts);
  row("ICP-only, OXTS velocities", real->icp_oxts_velocity, simulated->icp_oxts_velocity);
  row("lidar_only, OXTS velocities", real->lidar_only_oxts_velocity,
      simulated->lidar_only_oxts_velocity);
  md << "\nEach track's position increments over 1 s against the drive's OXTS velocities "
        "integrated, in % of the distance (RMS; along and across the motion, mean +- std; "
        "across + = to the left; windows under 5 m skipped; the last row: ICP-only against "
        "lidar_only, no reference):\n\n"
        "| drive, track | windows | RMS | along | across | vertical RMS |\n"
        "|---|---|---|---|---|---|\n";
  for (const DriveMeasures* d : {&*real, &*simulated}) {
    for (const auto& [name, a] : d->increments) {
      md << "| " << d->label << ", " << name << " | " << a.windows << " | "
         << Fmt("%.2f", a.rms_pct) << " | " << Fmt("%.2f", a.along_mean_pct) << " +- "
         << Fmt("%.2f", a.along_std_pct) << " | " << Fmt("%.2f", a.cross_mean_pct) << " +- "
         << Fmt("%.2f", a.cross_std_pct) << " | " << Fmt("%.2f", a.vertical_rms_pct) << " |\n";
    }
  }
  md << "\nMap entropy from ground-truth poses (r 0.5 m, voxel 0.1 m): real "
     << Fmt("%.3f", real->gt_map->mean_map_entropy) << ", sim "
     << Fmt("%.3f", simulated->gt_map->mean_map_entropy) << ".\n\n";
  md << "## Scan statistics (scalars: ratio sim / real within 0.8..1.2; histograms: "
        "total-variation distance <= 0.2)\n\n| statistic | real | sim | ratio or distance | met "
        "|\n|---|---|---|---|---|\n";
  for (const eval::StatisticComparison& c : stats) {
    md << "| " << c.name << (c.is_histogram ? " (mean)" : "") << " | " << Fmt("%.4g", c.real)
       << " | " << Fmt("%.4g", c.sim) << " | " << Fmt("%.3f", c.value) << " | "
       << (c.met ? "yes" : "no") << " |\n";
  }
  md << "\n" << stats_met << " of " << stats.size() << " statistics met.\n";
  {
    std::ofstream f(args.out / "report.md");
    f << md.str();
    if (!f) return Fail(DataLossError("cannot write " + (args.out / "report.md").string()));
  }
  std::fputs(md.str().c_str(), stdout);
  return 0;
}
