#include "slam_mms_run/cli.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace slam_mms::app {
namespace {

bool ParseDouble(const std::string& text, double* value) {
  if (text.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (errno != 0 || end != text.c_str() + text.size() || !std::isfinite(v)) return false;
  *value = v;
  return true;
}

bool ParseInt(const std::string& text, int64_t* value) {
  if (text.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (errno != 0 || end != text.c_str() + text.size()) return false;
  *value = v;
  return true;
}

Status ParseFrames(const std::string& text, RunArgs* args) {
  const size_t colon = text.find(':');
  const std::string bad = "--frames " + text + ": expected A:B (inclusive frame numbers, A <= B)";
  if (colon == std::string::npos) return InvalidArgumentError(bad);
  int64_t a = 0, b = -1;
  if (!ParseInt(text.substr(0, colon), &a) || a < 0) return InvalidArgumentError(bad);
  const std::string last = text.substr(colon + 1);
  if (!last.empty() && (!ParseInt(last, &b) || b < a)) return InvalidArgumentError(bad);
  args->first_frame = a;
  args->last_frame = last.empty() ? -1 : b;
  return OkStatus();
}

Status ParseOutage(const std::string& text, RunArgs* args) {
  const size_t colon = text.find(':');
  double start = 0.0, duration = 0.0;
  if (colon == std::string::npos || !ParseDouble(text.substr(0, colon), &start) ||
      !ParseDouble(text.substr(colon + 1), &duration) || start < 0.0 || duration <= 0.0) {
    return InvalidArgumentError("--gnss-outage " + text +
                                ": expected START_S:DURATION_S with START_S >= 0 and "
                                "DURATION_S > 0 (seconds from the first scan's start)");
  }
  args->gnss_outages.emplace_back(start, duration);
  return OkStatus();
}

}  // namespace

std::string RunUsage() {
  return R"(slam_mms_run: SLAM-integrated mobile mapping (Li et al. 2020) on a KITTI raw drive or a
simulated one; writes trajectories, maps, report.json and plots.

Usage:
  slam_mms_run --kitti-raw DRIVE_DIR --out DIR
               [--mode full|gnss_ins|gnss_ins_smoothed|lidar_only|all] [--pos forward|smoothed]
               [--frames A:B] [--gnss-outage START_S:DURATION_S ...] [--config FILE]
  slam_mms_run --folder DIR --out DIR [...]         a plain drive folder (PCD/PLY/bin + CSV/NMEA)
  slam_mms_run --rosbag FILE.bag --out DIR [--lidar-topic T] [--imu-topic T] [--gnss-topic T]
               [--extrinsics FILE.yaml] [...]       a ROS 1 bag
  slam_mms_run --out DIR [...]     no data: simulates the embedded default drive into DIR/sim,
                                   then runs on it (simulator ground truth)

Options:
  --kitti-raw DRIVE_DIR   KITTI raw drive folder (.../2011_09_26_drive_0013_sync); calibration
                          from the folder or its parent. Ground truth: DRIVE_DIR/ground_truth/
                          (simulated drives) when present, else the OXTS poses.
  --folder DIR            a plain drive folder: scans/ (PCD, PLY or KITTI .bin), scans.csv,
                          imu.csv, gnss.csv or gnss.nmea, extrinsics.yaml, optional
                          initial_state.csv and pos.csv (docs/drive_folder.md). Frames are scan
                          numbers in scans.csv order. Ground truth: DIR/ground_truth/ if present.
  --rosbag FILE.bag       a ROS 1 bag: sensor_msgs/PointCloud2, Imu, NavSatFix (docs/rosbag.md).
                          Ground truth: ground_truth/ beside the bag if present.
  --lidar-topic, --imu-topic, --gnss-topic T
                          bag topics (default: the one topic of each message type in the bag).
  --extrinsics FILE.yaml  T_body_lidar and t_body_antenna_m (the folder's extrinsics.yaml format);
                          for bags, and to override a folder's own.
  --out DIR               output folder (created).
  --mode M                full | gnss_ins | gnss_ins_smoothed | lidar_only | all (default all =
                          the four in turn). gnss_ins: scans on the forward GNSS/INS filter (the
                          real-time POS); gnss_ins_smoothed: on the forward-backward smoothed POS
                          (post-processed, as survey software does).
  --pos P                 forward | smoothed (default forward): the POS `full` runs on.
                          forward: the streaming workflow (the forward filter, F_Prein in
                          outages). smoothed: the offline workflow (the smoothed POS over the
                          whole drive first, F_Odom from it also in GNSS outages, raw fixes as
                          level-2 factors); not the default until it helps `full` (docs/results.md).
  --frames A:B            only frames A..B (inclusive file numbers); A: = from A to the end.
  --gnss-outage S:D       withhold GNSS fixes for D seconds from S seconds after the first scan's
                          start; repeat the flag or list several windows after it.
  --config FILE           "key = value" lines overriding MappingSystem options (keys in
                          docs/user_guide.md, "Options"); unknown keys and bad values are errors.
  --sim-duration S        seconds of the default drive to simulate (default 30; 0 = all ~3 min).
  --sim-seed N            simulator seed (default 1).
  --log-level L           debug | info | warning | error: the library's messages on stderr from
                          this level (default warning; info adds GNSS loss/return, POS jumps,
                          level-2 solves; debug adds loop candidates and per-submap events).
  --config-keys           print every --config key with its type and default, then exit.
  --help                  this text.

Outputs in DIR: <method>.tum, <method>.kitti, <method>_cov.csv per method; <method>_scans.csv
(per-scan level-1 results and stage times) and <method>_level1.tum (level 1 before level 2) for
full and lidar_only; ground_truth.tum (in the run's world frame, for slam_mms_eval); map_full and
map_gnss_ins(_smoothed) as .ply, .pcd and geo-referenced .las (UTM); report.json; summary.txt;
trajectories.png, position_error.png, map_<method>_height.png.
Exit status: 0 done; 1 input or processing error (outputs computed so far are written);
2 bad command line or config file.
)";
}

StatusOr<RunArgs> ParseRunArgs(int argc, const char* const* argv) {
  RunArgs args;
  bool mode_given = false;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    auto value = [&](std::string* out) -> Status {
      if (i + 1 >= argc) return InvalidArgumentError(flag + ": missing value");
      *out = argv[++i];
      return OkStatus();
    };
    std::string v;
    if (flag == "--help" || flag == "-h") {
      args.help = true;
    } else if (flag == "--config-keys") {
      args.list_config_keys = true;
    } else if (flag == "--kitti-raw") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      args.kitti_raw = v;
    } else if (flag == "--folder") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      args.folder = v;
    } else if (flag == "--rosbag") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      args.rosbag = v;
    } else if (flag == "--lidar-topic") {
      SLAM_MMS_RETURN_IF_ERROR(value(&args.lidar_topic));
    } else if (flag == "--imu-topic") {
      SLAM_MMS_RETURN_IF_ERROR(value(&args.imu_topic));
    } else if (flag == "--gnss-topic") {
      SLAM_MMS_RETURN_IF_ERROR(value(&args.gnss_topic));
    } else if (flag == "--extrinsics") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      args.extrinsics = v;
    } else if (flag == "--out") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      args.out_dir = v;
    } else if (flag == "--mode") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      if (mode_given) return InvalidArgumentError("--mode given twice");
      mode_given = true;
      MappingMode mode;
      if (v == "all") {
        args.modes = {MappingMode::kFull, MappingMode::kGnssIns, MappingMode::kGnssInsSmoothed,
                      MappingMode::kLidarOnly};
      } else if (ParseMappingMode(v, &mode)) {
        args.modes = {mode};
      } else {
        return InvalidArgumentError("--mode " + v +
                                    ": expected full, gnss_ins, gnss_ins_smoothed, lidar_only or "
                                    "all");
      }
    } else if (flag == "--pos") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      if (!ParsePosWorkflow(v, &args.pos)) {
        return InvalidArgumentError("--pos " + v + ": expected smoothed or forward");
      }
    } else if (flag == "--frames") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      SLAM_MMS_RETURN_IF_ERROR(ParseFrames(v, &args));
    } else if (flag == "--gnss-outage") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      SLAM_MMS_RETURN_IF_ERROR(ParseOutage(v, &args));
      while (i + 1 < argc && std::string(argv[i + 1]).rfind("--", 0) != 0) {
        SLAM_MMS_RETURN_IF_ERROR(ParseOutage(argv[++i], &args));
      }
    } else if (flag == "--config") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      args.config = v;
    } else if (flag == "--sim-duration") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      if (!ParseDouble(v, &args.sim_duration_s) || args.sim_duration_s < 0.0) {
        return InvalidArgumentError("--sim-duration " + v + ": expected seconds >= 0");
      }
    } else if (flag == "--log-level") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      if (v == "debug") {
        args.log_level = LogLevel::kDebug;
      } else if (v == "info") {
        args.log_level = LogLevel::kInfo;
      } else if (v == "warning") {
        args.log_level = LogLevel::kWarning;
      } else if (v == "error") {
        args.log_level = LogLevel::kError;
      } else {
        return InvalidArgumentError("--log-level " + v +
                                    ": expected debug, info, warning or error");
      }
    } else if (flag == "--sim-seed") {
      SLAM_MMS_RETURN_IF_ERROR(value(&v));
      int64_t seed = 0;
      if (!ParseInt(v, &seed) || seed < 0) {
        return InvalidArgumentError("--sim-seed " + v + ": expected an integer >= 0");
      }
      args.sim_seed = static_cast<uint64_t>(seed);
    } else {
      return InvalidArgumentError("unknown argument '" + flag + "' (see --help)");
    }
  }
  if (args.help || args.list_config_keys) return args;
  if (args.out_dir.empty()) return InvalidArgumentError("--out DIR is required (see --help)");
  const int inputs = !args.kitti_raw.empty() + !args.folder.empty() + !args.rosbag.empty();
  if (inputs > 1) {
    return InvalidArgumentError("--kitti-raw, --folder and --rosbag exclude each other");
  }
  if (args.rosbag.empty() &&
      !(args.lidar_topic.empty() && args.imu_topic.empty() && args.gnss_topic.empty())) {
    return InvalidArgumentError("--lidar-topic/--imu-topic/--gnss-topic go with --rosbag");
  }
  if (!mode_given) {
    args.modes = {MappingMode::kFull, MappingMode::kGnssIns, MappingMode::kGnssInsSmoothed,
                  MappingMode::kLidarOnly};
  }
  return args;
}

}  // namespace slam_mms::app
