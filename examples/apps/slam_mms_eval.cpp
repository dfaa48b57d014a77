// slam_mms_eval: evaluates any TUM/KITTI trajectory against a TUM ground truth, and any PLY/PCD
// map's mean map entropy, so other systems' outputs can be compared on the same footing as
// slam_mms_run's (same metrics code, same conventions: no alignment unless asked, the ground truth
// interpolated at each estimated pose's own stamp).
//
//   slam_mms_eval --gt GT.tum --est [NAME=]FILE ... [--map [NAME=]FILE.ply|pcd ...]
//                 [--align none|se3|sim3] [--segments kitti|short] [--outage START_S:DURATION_S
//                 ...]
//                 [--t0 SECONDS] [--format auto|tum|kitti] [--kitti-times FILE]
//                 [--radius M] [--voxel M] [--min-neighbors N] [--threads N]
//                 [--json OUT.json] [--plots DIR]
//
// Prints a table; --json writes every number (with the entropy options and counts); --plots writes
// trajectories.png, position_error.png and map_<NAME>.png.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/eval/outage_error.hpp"
#include "slam_mms/eval/plots.hpp"
#include "slam_mms/eval/relative_error.hpp"
#include "slam_mms/eval/trajectory_error.hpp"
#include "slam_mms/io/map_io.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms/version.hpp"

namespace fs = std::filesystem;
using namespace slam_mms;        // NOLINT(google-build-using-namespace)
using namespace slam_mms::eval;  // NOLINT(google-build-using-namespace)

namespace {

const char* kUsage =
    "usage: slam_mms_eval --gt GT.tum --est [NAME=]FILE ... [--map [NAME=]FILE.ply|.pcd ...]\n"
    "         [--align none|se3|sim3] [--segments kitti|short] [--outage START_S:DURATION_S ...]\n"
    "         [--t0 SECONDS] [--format auto|tum|kitti] [--kitti-times FILE]\n"
    "         [--radius M] [--voxel M] [--min-neighbors N] [--threads N]\n"
    "         [--json OUT.json] [--plots DIR]\n"
    "       slam_mms_eval --version | --help\n"
    "\n"
    "  --gt           ground truth, TUM (t tx ty tz qx qy qz qw), same world frame as the "
    "estimates\n"
    "  --est          an estimated trajectory, TUM or KITTI (12 numbers a line); repeatable\n"
    "  --map          a map (PLY or PCD) whose mean map entropy is computed; repeatable\n"
    "  --align        none (default: geo-referenced outputs are compared as given), se3, sim3\n"
    "  --segments     kitti: 100..800 m (devkit); short: 10..80 m for short drives\n"
    "  --outage       a GNSS-outage window, seconds after t0; repeatable\n"
    "  --t0           reference time of the outage windows [s since epoch]; default: first\n"
    "                 stamp of the first estimate\n"
    "  --format       trajectory format of --est; auto decides per file by numbers a line (8 or "
    "12)\n"
    "  --kitti-times  stamps for KITTI files (one time in seconds a line); default: "
    "<stem>_times.txt\n"
    "                 or times.txt beside the file, else a KITTI file must have one pose per\n"
    "                 ground-truth pose and takes the ground truth's stamps\n"
    "  --radius, --voxel, --min-neighbors, --threads   entropy options (0.5 m, 0.1 m, 5, 2)\n"
    "  --json         write all numbers as JSON\n"
    "  --plots        write PNG plots into this folder\n"
    "  Values go after the flag or after '=' (--json=OUT.json).\n";

struct Named {
  std::string name;
  fs::path file;
};

struct Args {
  fs::path gt;
  std::vector<Named> estimates;
  std::vector<Named> maps;
  Alignment alignment = Alignment::kNone;
  RelativeErrorOptions segments = RelativeErrorOptions::Kitti();
  std::vector<OutageWindow> outages;
  bool has_t0 = false;
  Timestamp t0;
  std::string format = "auto";
  fs::path kitti_times;
  MapEntropyOptions entropy;
  fs::path json;
  fs::path plots;
};

Named ParseNamed(const std::string& v) {
  const size_t eq = v.find('=');
  if (eq != std::string::npos && eq > 0) return {v.substr(0, eq), v.substr(eq + 1)};
  return {fs::path(v).stem().string(), v};
}

bool ParseDouble(const std::string& s, double* out) {
  char* end = nullptr;
  *out = std::strtod(s.c_str(), &end);
  return end != s.c_str() && *end == '\0' && std::isfinite(*out);
}

// The command line (CLI11: `--flag value` and `--flag=value`); values are taken as text and checked
// here so that the messages say what was expected. "help" / "version": print and exit 0.
StatusOr<Args> ParseArgs(int argc, char** argv) {
  Args a;
  CLI::App app("slam_mms_eval", "slam_mms_eval");
  app.set_help_flag();
  bool help = false, version = false;
  std::vector<std::string> est, maps, outages;
  std::string gt, align, segments, t0, format, kitti_times, radius, voxel, min_neighbors, threads,
      json, plots;
  app.add_flag("-h,--help", help);
  app.add_flag("--version", version);
  app.add_option("--gt", gt);
  app.add_option("--est", est)->expected(1, CLI::detail::expected_max_vector_size);
  app.add_option("--map", maps)->expected(1, CLI::detail::expected_max_vector_size);
  app.add_option("--align", align);
  app.add_option("--segments", segments);
  app.add_option("--outage", outages)->expected(1, CLI::detail::expected_max_vector_size);
  app.add_option("--t0", t0);
  app.add_option("--format", format);
  app.add_option("--kitti-times", kitti_times);
  app.add_option("--radius", radius);
  app.add_option("--voxel", voxel);
  app.add_option("--min-neighbors", min_neighbors);
  app.add_option("--threads", threads);
  app.add_option("--json", json);
  app.add_option("--plots", plots);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return InvalidArgumentError(e.what());
  }
  if (help) return NotFoundError("help");
  if (version) return NotFoundError("version");
  const auto given = [&app](const char* flag) { return app.count(flag) > 0; };
  a.gt = gt;
  for (const std::string& v : est) a.estimates.push_back(ParseNamed(v));
  for (const std::string& v : maps) a.maps.push_back(ParseNamed(v));
  if (given("--align")) {
    if (align == "none")
      a.alignment = Alignment::kNone;
    else if (align == "se3")
      a.alignment = Alignment::kSe3;
    else if (align == "sim3")
      a.alignment = Alignment::kSim3;
    else
      return InvalidArgumentError("--align " + align + ": must be none, se3 or sim3");
  }
  if (given("--segments")) {
    if (segments == "kitti")
      a.segments = RelativeErrorOptions::Kitti();
    else if (segments == "short")
      a.segments = RelativeErrorOptions::ShortDrive();
    else
      return InvalidArgumentError("--segments " + segments + ": must be kitti or short");
  }
  for (const std::string& v : outages) {
    const size_t colon = v.find(':');
    OutageWindow w;
    if (colon == std::string::npos || !ParseDouble(v.substr(0, colon), &w.start_s) ||
        !ParseDouble(v.substr(colon + 1), &w.duration_s) || !(w.duration_s > 0.0)) {
      return InvalidArgumentError("--outage " + v + ": expected START_S:DURATION_S, duration > 0");
    }
    a.outages.push_back(w);
  }
  if (given("--t0")) {
    SLAM_MMS_ASSIGN_OR_RETURN(a.t0, ParseSecondsExact(t0));
    a.has_t0 = true;
  }
  if (given("--format")) {
    a.format = format;
    if (a.format != "auto" && a.format != "tum" && a.format != "kitti") {
      return InvalidArgumentError("--format " + a.format + ": must be auto, tum or kitti");
    }
  }
  a.kitti_times = kitti_times;
  const auto number = [&](const char* flag, const std::string& v, double* out) -> Status {
    if (given(flag) && !ParseDouble(v, out)) {
      return InvalidArgumentError(std::string(flag) + " " + v + ": not a number");
    }
    return OkStatus();
  };
  SLAM_MMS_RETURN_IF_ERROR(number("--radius", radius, &a.entropy.radius_m));
  SLAM_MMS_RETURN_IF_ERROR(number("--voxel", voxel, &a.entropy.voxel_size_m));
  double d = a.entropy.min_neighbors;
  SLAM_MMS_RETURN_IF_ERROR(number("--min-neighbors", min_neighbors, &d));
  a.entropy.min_neighbors = static_cast<int>(d);
  d = a.entropy.num_threads;
  SLAM_MMS_RETURN_IF_ERROR(number("--threads", threads, &d));
  a.entropy.num_threads = static_cast<int>(d);
  a.json = json;
  a.plots = plots;
  if (a.estimates.empty() && a.maps.empty()) {
    return InvalidArgumentError("nothing to evaluate: give --est (with --gt) and/or --map");
  }
  if (!a.estimates.empty() && a.gt.empty()) return InvalidArgumentError("--est needs --gt");
  SLAM_MMS_RETURN_IF_ERROR(a.entropy.Validate());
  return a;
}

// Numbers on the first data line: 8 (TUM) or 12 (KITTI).
StatusOr<std::string> DetectFormat(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return NotFoundError("cannot open " + file.string());
  std::string line;
  while (std::getline(in, line)) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream s(line);
    std::string tok;
    int n = 0;
    while (s >> tok) ++n;
    if (n == 8) return std::string("tum");
    if (n == 12) return std::string("kitti");
    return InvalidArgumentError(file.string() + ": first data line has " + std::to_string(n) +
                                " numbers; expected 8 (TUM) or 12 (KITTI); use --format");
  }
  return DataLossError(file.string() + ": no data line");
}

StatusOr<std::vector<Timestamp>> ReadTimes(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return NotFoundError("cannot open " + file.string());
  std::vector<Timestamp> stamps;
  std::string line;
  for (int l = 1; std::getline(in, line); ++l) {
    std::istringstream s(line);
    std::string tok;
    if (!(s >> tok)) continue;
    StatusOr<Timestamp> t = ParseSecondsExact(tok);
    if (!t.ok()) return t.status().WithContext(file.string() + ":" + std::to_string(l));
    stamps.push_back(*t);
  }
  return stamps;
}

StatusOr<Trajectory> LoadEstimate(const Args& a, const fs::path& file, const Trajectory& gt) {
  std::string format = a.format;
  if (format == "auto") {
    SLAM_MMS_ASSIGN_OR_RETURN(format, DetectFormat(file));
  }
  if (format == "tum") return ReadTrajectoryTum(file);
  std::vector<Timestamp> stamps;
  // Without --kitti-times: <stem>_times.txt beside the file (slam_mms_run writes one beside every
  // .kitti), else KITTI odometry's times.txt in the same folder.
  fs::path times = a.kitti_times;
  if (times.empty()) {
    for (const fs::path& candidate : {file.parent_path() / (file.stem().string() + "_times.txt"),
                                      file.parent_path() / "times.txt"}) {
      std::error_code ec;
      if (fs::is_regular_file(candidate, ec)) {
        times = candidate;
        break;
      }
    }
  }
  if (!times.empty()) {
    SLAM_MMS_ASSIGN_OR_RETURN(stamps, ReadTimes(times));
  } else {
    SLAM_MMS_ASSIGN_OR_RETURN(const std::vector<Eigen::Isometry3d> poses, ReadPosesKitti(file));
    if (poses.size() != gt.size()) {
      return InvalidArgumentError(
          file.string() + ": KITTI file with " + std::to_string(poses.size()) +
          " poses has no stamps and the ground truth has " + std::to_string(gt.size()) +
          " poses; give --kitti-times or a ground truth with one pose per line");
    }
    for (const StampedPose& p : gt.poses()) stamps.push_back(p.stamp);
  }
  return ReadTrajectoryKitti(file, stamps);
}

StatusOr<MapCloud> LoadMap(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext == ".ply") return ReadPly(file);
  if (ext == ".pcd") return ReadPcd(file);
  return InvalidArgumentError(file.string() + ": unknown map format (expected .ply or .pcd)");
}

struct TrajectoryEval {
  std::string name;
  fs::path file;
  Trajectory trajectory;
  AteResult ate;
  RelativeErrorResult rel;
  OutageErrorResult outage;
};

struct MapEval {
  std::string name;
  fs::path file;
  MapEntropyResult result;
};

std::string Fmt(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  return buf;
}

void PrintTables(const Args& a, const std::vector<TrajectoryEval>& traj,
                 const std::vector<MapEval>& maps) {
  if (!traj.empty()) {
    std::printf("\nTrajectories vs %s  (alignment: %s; relative error: %s; %zu outage window(s))\n",
                a.gt.string().c_str(), AlignmentName(a.alignment),
                a.segments.LengthsLabel().c_str(), a.outages.size());
    std::printf("%-14s %6s %6s %8s %23s %8s %23s %8s %11s %9s %9s\n", "method", "poses", "unmat",
                "ATE[m]", "ATE x/y/z [m]", "rot[deg]", "rot r/p/y [deg]", "t_rel[%]", "r_rel[d/hm]",
                "outPos[m]", "outRot[d]");
    for (const TrajectoryEval& t : traj) {
      const std::string xyz = Fmt(t.ate.ate_rmse_xyz_m.x(), 3) + "/" +
                              Fmt(t.ate.ate_rmse_xyz_m.y(), 3) + "/" +
                              Fmt(t.ate.ate_rmse_xyz_m.z(), 3);
      const std::string rpy = Fmt(t.ate.rot_rmse_rpy_deg.x(), 3) + "/" +
                              Fmt(t.ate.rot_rmse_rpy_deg.y(), 3) + "/" +
                              Fmt(t.ate.rot_rmse_rpy_deg.z(), 3);
      const bool out = t.outage.num_poses > 0;
      std::printf("%-14s %6zu %6zu %8s %23s %8s %23s %8s %11s %9s %9s\n", t.name.c_str(),
                  t.ate.num_matched, t.ate.num_unmatched, Fmt(t.ate.ate_rmse_m, 3).c_str(),
                  xyz.c_str(), Fmt(t.ate.rot_rmse_deg, 3).c_str(), rpy.c_str(),
                  Fmt(t.rel.t_rel_pct, 3).c_str(), Fmt(t.rel.r_rel_deg_per_100m, 3).c_str(),
                  out ? Fmt(t.outage.max_pos_err_m, 3).c_str() : "-",
                  out ? Fmt(t.outage.max_rot_err_deg, 3).c_str() : "-");
    }
  }
  if (!maps.empty()) {
    const MapEntropyOptions& o = a.entropy;
    std::printf(
        "\nMaps  (mean map entropy, eqs 26-27: r = %.3g m, voxel %.3g m, min %d neighbours)\n",
        o.radius_m, o.voxel_size_m, o.min_neighbors);
    std::printf("%-14s %10s %10s %10s %8s %8s %10s %14s\n", "map", "points", "evaluated", "valid",
                "sparse", "degen", "MME", "plane var[m2]");
    for (const MapEval& m : maps) {
      const MapEntropyResult& r = m.result;
      std::printf("%-14s %10zu %10zu %10zu %8zu %8zu %10s %14.4e\n", m.name.c_str(),
                  r.num_input_points, r.num_evaluated_points, r.num_valid_points,
                  r.num_sparse_points, r.num_degenerate_points, Fmt(r.mean_map_entropy, 4).c_str(),
                  r.mean_plane_variance_m2);
    }
  }
}

using Json = nlohmann::ordered_json;

// A number, null where not finite (no segment, no pose in an outage).
Json Num(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
Json Vec(const Eigen::Vector3d& v) { return Json::array({Num(v.x()), Num(v.y()), Num(v.z())}); }

std::string ToJson(const Args& a, const std::vector<TrajectoryEval>& traj,
                   const std::vector<MapEval>& maps, Timestamp t0) {
  Json j = Json::object();
  j["version"] = SLAM_MMS_VERSION_STRING;
  j["ground_truth"] = a.gt.string();
  j["alignment"] = AlignmentName(a.alignment);
  j["relative_error_lengths"] = a.segments.LengthsLabel();
  j["t0_s"] = FormatSecondsExact(t0);
  Json outages = Json::array();
  for (const OutageWindow& o : a.outages) outages.push_back({Num(o.start_s), Num(o.duration_s)});
  j["gnss_outages"] = std::move(outages);
  Json trajectories = Json::object();
  for (const TrajectoryEval& t : traj) {
    const bool out = t.outage.num_poses > 0;
    const Json null(nullptr);
    Json e = Json::object();
    e["file"] = t.file.string();
    e["num_matched"] = t.ate.num_matched;
    e["num_unmatched"] = t.ate.num_unmatched;
    e["ate_rmse_m"] = Num(t.ate.ate_rmse_m);
    e["ate_rmse_xyz_m"] = Vec(t.ate.ate_rmse_xyz_m);
    e["ate_mean_m"] = Num(t.ate.ate_mean_m);
    e["ate_median_m"] = Num(t.ate.ate_median_m);
    e["ate_max_m"] = Num(t.ate.ate_max_m);
    e["rot_rmse_deg"] = Num(t.ate.rot_rmse_deg);
    e["rot_rmse_rpy_deg"] = Vec(t.ate.rot_rmse_rpy_deg);
    e["rot_mean_rpy_deg"] = Vec(t.ate.rot_mean_rpy_deg);
    e["t_rel_pct"] = Num(t.rel.t_rel_pct);
    e["r_rel_deg_per_100m"] = Num(t.rel.r_rel_deg_per_100m);
    e["relative_error_segments"] = t.rel.num_segments;
    e["max_pos_err_in_outage_m"] = out ? Num(t.outage.max_pos_err_m) : null;
    e["rms_pos_err_in_outage_m"] = out ? Num(t.outage.rms_pos_err_m) : null;
    e["max_rot_err_in_outage_deg"] = out ? Num(t.outage.max_rot_err_deg) : null;
    e["rms_rot_err_in_outage_deg"] = out ? Num(t.outage.rms_rot_err_deg) : null;
    trajectories[t.name] = std::move(e);
  }
  j["trajectories"] = std::move(trajectories);
  Json jmaps = Json::object();
  for (const MapEval& m : maps) {
    const MapEntropyResult& r = m.result;
    jmaps[m.name] = Json{{"file", m.file.string()},
                         {"mme", Num(r.mean_map_entropy)},
                         {"mean_plane_variance_m2", Num(r.mean_plane_variance_m2)},
                         {"radius_m", Num(r.options.radius_m)},
                         {"voxel_size_m", Num(r.options.voxel_size_m)},
                         {"min_neighbors", r.options.min_neighbors},
                         {"num_input_points", r.num_input_points},
                         {"num_evaluated_points", r.num_evaluated_points},
                         {"num_valid_points", r.num_valid_points},
                         {"num_sparse_points", r.num_sparse_points},
                         {"num_degenerate_points", r.num_degenerate_points}};
  }
  j["maps"] = std::move(jmaps);
  return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

Status Run(const Args& a) {
  std::vector<TrajectoryEval> traj;
  std::vector<MapEval> maps;
  Trajectory gt;
  Timestamp t0 = a.t0;
  if (!a.estimates.empty()) {
    SLAM_MMS_ASSIGN_OR_RETURN(gt, ReadTrajectoryTum(a.gt));
    for (const Named& e : a.estimates) {
      TrajectoryEval t;
      t.name = e.name;
      t.file = e.file;
      SLAM_MMS_ASSIGN_OR_RETURN(t.trajectory, LoadEstimate(a, e.file, gt));
      if (t.trajectory.empty()) return InvalidArgumentError(e.file.string() + ": no pose");
      if (!a.has_t0 && traj.empty()) t0 = t.trajectory.start();
      AteOptions ate_options;
      ate_options.alignment = a.alignment;
      StatusOr<AteResult> ate = ComputeAte(t.trajectory, gt, ate_options);
      if (!ate.ok()) return ate.status().WithContext(e.file.string());
      t.ate = std::move(*ate);
      // The relative error is invariant to a rigid alignment; with Sim(3) it sees the scaled poses.
      MatchedPoses matched;
      SLAM_MMS_ASSIGN_OR_RETURN(matched, MatchByTimestamp(t.trajectory, gt));
      if (a.alignment == Alignment::kSim3) {
        for (Eigen::Isometry3d& T : matched.T_world_est) {
          T.translation() = t.ate.T_gt_est * Eigen::Vector3d(T.translation());
          T.linear() = t.ate.T_gt_est.R * T.linear();
        }
      }
      SLAM_MMS_ASSIGN_OR_RETURN(
          t.rel, ComputeRelativeError(matched.T_world_gt, matched.T_world_est, a.segments));
      traj.push_back(std::move(t));
    }
    for (TrajectoryEval& t : traj) {
      SLAM_MMS_ASSIGN_OR_RETURN(t.outage, ComputeOutageErrors(t.ate.errors, a.outages, t0));
    }
  }
  for (const Named& m : a.maps) {
    std::fprintf(stderr, "computing the entropy of %s ...\n", m.file.string().c_str());
    SLAM_MMS_ASSIGN_OR_RETURN(const MapCloud map, LoadMap(m.file));
    StatusOr<MapEntropyResult> r = ComputeMapEntropy(map.cloud, a.entropy);
    if (!r.ok()) return r.status().WithContext(m.file.string());
    maps.push_back({m.name, m.file, *r});
  }
  PrintTables(a, traj, maps);

  if (!a.json.empty()) {
    const std::string text = ToJson(a, traj, maps, t0);
    std::ofstream out(a.json, std::ios::binary | std::ios::trunc);
    if (!(out << text)) return NotFoundError("cannot write " + a.json.string());
    std::printf("\nwrote %s\n", a.json.string().c_str());
  }
  if (!a.plots.empty()) {
    std::error_code ec;
    fs::create_directories(a.plots, ec);
    if (!traj.empty()) {
      std::vector<NamedTrajectory> methods;
      std::vector<ErrorSeries> series;
      for (const TrajectoryEval& t : traj) {
        methods.push_back({t.name, t.trajectory});
        series.push_back(MakeErrorSeries(t.name, t.ate.errors, t0));
      }
      SLAM_MMS_RETURN_IF_ERROR(PlotTrajectoriesTopView({"ground truth", gt}, methods, a.outages, t0,
                                                       a.plots / "trajectories.png"));
      std::vector<OutageWindow> outages = a.outages;
      PlotOptions wide;
      wide.height_px = 600;
      SLAM_MMS_RETURN_IF_ERROR(
          PlotPositionErrors(series, outages, a.plots / "position_error.png", wide));
    }
    for (const MapEval& m : maps) {
      SLAM_MMS_ASSIGN_OR_RETURN(const MapCloud map, LoadMap(m.file));
      std::vector<Eigen::Vector3d> overlay;
      for (const StampedPose& p : gt.poses()) overlay.push_back(p.T_world_body.translation());
      PlotOptions o;
      o.title = "Map " + m.name + " from above, coloured by height";
      SLAM_MMS_RETURN_IF_ERROR(
          PlotMapHeight(map.cloud, overlay, a.plots / ("map_" + m.name + ".png"), o));
    }
    std::printf("wrote plots to %s\n", a.plots.string().c_str());
  }
  return OkStatus();
}

}  // namespace

int main(int argc, char** argv) {
  SetLogSink(StderrLogSink());
  StatusOr<Args> args = ParseArgs(argc, argv);
  if (!args.ok()) {
    if (args.status().message() == "help") {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args.status().message() == "version") {
      std::printf("slam_mms_eval %s\n", SLAM_MMS_VERSION_STRING);
      return 0;
    }
    std::fprintf(stderr, "slam_mms_eval: %s\n\n%s", args.status().message().c_str(), kUsage);
    return 2;
  }
  const Status s = Run(*args);
  if (!s.ok()) {
    std::fprintf(stderr, "slam_mms_eval: %s\n", s.ToString().c_str());
    return 1;
  }
  return 0;
}
