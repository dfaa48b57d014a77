#include "slam_mms_run/cli.hpp"

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "slam_mms/version.hpp"

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

// EPSG:nnnn (what --crs takes; PROJ checks that the code exists when the outputs are written).
bool ValidCrsText(const std::string& text) {
  if (text.size() < 6 || text.compare(0, 5, "EPSG:") != 0) return false;
  for (size_t i = 5; i < text.size(); ++i) {
    if (text[i] < '0' || text[i] > '9') return false;
  }
  return text.size() <= 15;
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
  --extrinsics FILE       T_body_lidar, t_body_antenna_m and lidar_time_offset_s: a YAML file
                          (.yaml/.yml, the folder's extrinsics.yaml format) or KITTI's
                          calib_imu_to_velo.txt format (what --calibrate-extrinsics writes); for
                          bags, and to override a folder's or a KITTI drive's own.
  --imu-noise FILE        the IMU's noise from its datasheet (imu_noise.yaml format: angle and
                          velocity random walk, bias instability and correlation time; see
                          docs/drive_folder.md) for the POS filter and level 1's preintegration,
                          over the input's own imu_noise.yaml (used where config
                          use_stated_imu_noise is on; --imu-noise turns it on). Otherwise the
                          filter's defaults, an IMU of unknown grade.
  --kitti-vertical-correction DEG
                          KITTI's own recordings: every point rotated up by DEG (0.205, as
                          KISS-ICP and CT-ICP do: KITTI's HDL-64E writes points about 0.2 deg too
                          low, which tilts LiDAR-only odometry in pitch). KITTI raw drives and
                          folders of KITTI .bin scans; not for other sensors or the simulator.
  --kitti-oxts-delay auto|SECONDS
                          KITTI raw drives: stamp each IMU sample (the OXTS rates and
                          accelerations) SECONDS before its record. KITTI's OXTS writes them
                          about 50 ms behind its positions, attitudes and the LiDAR; auto (the
                          default) estimates the delay from the records (rates against the
                          attitudes' derivative) and applies it where it is clear (0 for the
                          simulator's records); 0 = as recorded.
  --calibrate-extrinsics  estimate the LiDAR boresight, lever arm and clock offset from the drive
                          against the offline POS first, write DIR/calib_imu_to_velo_estimated.txt
                          and report.json "extrinsics", and run with the estimate (config key
                          drive.estimate_extrinsics; docs/calibration.md).
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
  --config FILE           a YAML file overriding MappingSystem options (nested or dotted keys:
                          `localizer: {submap_duration_s: 2.0}` or `level2.use_loops: false`;
                          keys in docs/user_guide.md, "Options"); unknown keys, values of the
                          wrong type and keys given twice are errors naming file:line and key.
  --preset NAME           the LiDAR: hdl64e (default, KITTI), hdl32e, vlp16, os1_64; sets the
                          range-image geometry before --config (config key `preset`).
  --dump-config FILE      write the effective options (defaults + --config) as YAML, every key
                          commented with its type and default, then exit (--config reads it back).
  --crs EPSG:nnnn         output CRS of the LAS maps and the <method>_<crs>.csv trajectories
                          (default: WGS 84 / UTM zone of the world origin).
  --las-tile-size M       split LAS maps into square tiles of M metres (default 0 = one file).
  --resume                continue a killed run from DIR/checkpoint (same command line): its
                          finished methods are read back, the rest run (a method that was running
                          starts again from the first scan).
  --drive-result          write the full method's drive result (submaps, their clouds and level-2
                          factors) to DIR/drive_result for slam_mms_merge (docs/merge.md).
  --checkpoint-every N    while a method runs, write its trajectory so far every N finished
                          submaps (default 10; 0 = never); finished methods are always recorded.
  --sim-scenario NAME     the drive simulated without input data: demo (default: one city block
                          with four turns and a revisit, ~60 s), default (190 s) or long.
  --sim-duration S        seconds of that drive to simulate (default 0 = all of it).
  --sim-seed N            simulator seed (default 1).
  --keep-sim              keep the simulated default drive in DIR/sim (default: removed at the end).
  --log-level L           debug | info | warning | error: the library's messages on stderr from
                          this level (default warning; info adds GNSS loss/return, POS jumps,
                          level-2 solves; debug adds loop candidates and per-submap events).
  --config-keys           print every --config key with its default value as YAML (a --config
                          file; each key commented with its type), then exit.
  --version               print "slam_mms_run <version>" and exit.
  --help                  this text.
Values go after the flag or after '=': --out DIR or --out=DIR.

Outputs in DIR: <method>.tum, <method>.kitti, <method>_cov.csv per method; <method>_scans.csv
(per-scan level-1 results and stage times) and <method>_level1.tum (level 1 before level 2) for
full and lidar_only; ground_truth.tum (in the run's world frame, for slam_mms_eval); map_full and
map_gnss_ins(_smoothed) as .ply, .pcd and geo-referenced .las (UTM); report.json; summary.txt;
trajectories.png, position_error.png, map_<method>_height.png.
Exit status: 0 done; 1 input or processing error (outputs computed so far are written);
2 bad command line or config file.
)";
}

std::string RunVersion() { return std::string("slam_mms_run ") + SLAM_MMS_VERSION_STRING; }

StatusOr<RunArgs> ParseRunArgs(int argc, const char* const* argv) {
  RunArgs args;
  for (int i = 0; i < argc; ++i) args.command_line.emplace_back(argv[i]);
  // Every value is taken as text and checked below, so that the messages say what was expected.
  CLI::App app("slam_mms_run", "slam_mms_run");
  app.set_help_flag();  // --help is a flag of RunArgs (main prints RunUsage()).
  app.allow_windows_style_options(false);
  std::string kitti_raw, folder, rosbag, extrinsics, imu_noise, out, mode, pos, frames, config,
      sim_duration, sim_seed, log_level, dump_config, las_tile_size, checkpoint_every, preset,
      vertical_correction, oxts_delay;
  std::vector<std::string> outages;
  app.add_flag("-h,--help", args.help);
  app.add_flag("--version", args.version);
  app.add_flag("--config-keys", args.list_config_keys);
  app.add_option("--kitti-raw", kitti_raw);
  app.add_option("--folder", folder);
  app.add_option("--rosbag", rosbag);
  app.add_option("--lidar-topic", args.lidar_topic);
  app.add_option("--imu-topic", args.imu_topic);
  app.add_option("--gnss-topic", args.gnss_topic);
  app.add_option("--extrinsics", extrinsics);
  app.add_option("--imu-noise", imu_noise);
  app.add_option("--kitti-vertical-correction", vertical_correction);
  app.add_option("--kitti-oxts-delay", oxts_delay);
  app.add_option("--out", out);
  app.add_option("--mode", mode);
  app.add_option("--pos", pos);
  app.add_option("--frames", frames);
  // Repeatable, and several windows may follow one flag.
  app.add_option("--gnss-outage", outages)->expected(1, CLI::detail::expected_max_vector_size);
  app.add_option("--config", config);
  app.add_option("--preset", preset);
  app.add_option("--dump-config", dump_config);
  app.add_option("--sim-scenario", args.sim_scenario);
  app.add_option("--sim-duration", sim_duration);
  app.add_option("--sim-seed", sim_seed);
  app.add_flag("--keep-sim", args.keep_sim);
  app.add_flag("--drive-result", args.drive_result);
  app.add_flag("--calibrate-extrinsics", args.calibrate_extrinsics);
  app.add_option("--log-level", log_level);
  app.add_option("--crs", args.crs);
  app.add_option("--las-tile-size", las_tile_size);
  app.add_flag("--resume", args.resume);
  app.add_option("--checkpoint-every", checkpoint_every);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ExtrasError& e) {
    return InvalidArgumentError(std::string(e.what()) + " (unknown argument; see --help)");
  } catch (const CLI::ParseError& e) {
    std::string message = e.what();
    if (message.find("At Most 1 required but received") != std::string::npos) {
      message = message.substr(0, message.find(':')) + " given twice";
    }
    return InvalidArgumentError(message + " (see --help)");
  }
  const auto given = [&app](const char* flag) { return app.count(flag) > 0; };
  args.kitti_raw = kitti_raw;
  args.folder = folder;
  args.rosbag = rosbag;
  args.extrinsics = extrinsics;
  args.imu_noise = imu_noise;
  args.out_dir = out;
  args.config = config;
  if (given("--preset")) {
    auto parsed = ParseLidarPreset(preset);
    if (!parsed.ok()) return InvalidArgumentError("--preset: " + parsed.status().message());
    args.preset = *parsed;
  }
  args.dump_config = dump_config;
  if (given("--mode")) {
    MappingMode m;
    if (mode == "all") {
      args.modes = {MappingMode::kFull, MappingMode::kGnssIns, MappingMode::kGnssInsSmoothed,
                    MappingMode::kLidarOnly};
    } else if (ParseMappingMode(mode, &m)) {
      args.modes = {m};
    } else {
      return InvalidArgumentError("--mode " + mode +
                                  ": expected full, gnss_ins, gnss_ins_smoothed, lidar_only or "
                                  "all");
    }
  }
  if (given("--pos") && !ParsePosWorkflow(pos, &args.pos)) {
    return InvalidArgumentError("--pos " + pos + ": expected smoothed or forward");
  }
  if (given("--frames")) SLAM_MMS_RETURN_IF_ERROR(ParseFrames(frames, &args));
  if (given("--kitti-vertical-correction") &&
      (!ParseDouble(vertical_correction, &args.kitti_vertical_correction_deg) ||
       !(std::abs(args.kitti_vertical_correction_deg) <= 5.0))) {
    return InvalidArgumentError("--kitti-vertical-correction " + vertical_correction +
                                ": expected degrees within [-5, 5] (KITTI: 0.205)");
  }
  if (args.kitti_vertical_correction_deg != 0.0 && args.kitti_raw.empty() && args.folder.empty()) {
    return InvalidArgumentError(
        "--kitti-vertical-correction is for KITTI's own recordings (--kitti-raw, or --folder "
        "with KITTI .bin scans), not for a bag or the simulated drive");
  }
  if (given("--kitti-oxts-delay") && oxts_delay != "auto") {
    double d = 0.0;
    if (!ParseDouble(oxts_delay, &d) || !(std::abs(d) <= 0.5)) {
      return InvalidArgumentError("--kitti-oxts-delay " + oxts_delay +
                                  ": expected auto or seconds within [-0.5, 0.5] (KITTI: 0.05)");
    }
    args.kitti_oxts_inertial_delay_s = d;
  }
  if (given("--kitti-oxts-delay") && args.kitti_raw.empty()) {
    return InvalidArgumentError(
        "--kitti-oxts-delay is for KITTI raw drives (--kitti-raw): the OXTS records' timing");
  }
  for (const std::string& o : outages) SLAM_MMS_RETURN_IF_ERROR(ParseOutage(o, &args));
  if (args.sim_scenario != "demo" && args.sim_scenario != "default" &&
      args.sim_scenario != "long") {
    return InvalidArgumentError("--sim-scenario " + args.sim_scenario +
                                ": expected demo, default or long");
  }
  if (given("--sim-duration") &&
      (!ParseDouble(sim_duration, &args.sim_duration_s) || args.sim_duration_s < 0.0)) {
    return InvalidArgumentError("--sim-duration " + sim_duration + ": expected seconds >= 0");
  }
  if (given("--sim-seed")) {
    int64_t seed = 0;
    if (!ParseInt(sim_seed, &seed) || seed < 0) {
      return InvalidArgumentError("--sim-seed " + sim_seed + ": expected an integer >= 0");
    }
    args.sim_seed = static_cast<uint64_t>(seed);
  }
  if (given("--log-level") && !ParseLogLevel(log_level, &args.log_level)) {
    return InvalidArgumentError("--log-level " + log_level +
                                ": expected debug, info, warning or error");
  }
  if (given("--las-tile-size") &&
      (!ParseDouble(las_tile_size, &args.las_tile_size_m) || args.las_tile_size_m < 0.0)) {
    return InvalidArgumentError("--las-tile-size " + las_tile_size +
                                ": expected metres >= 0 (0 = one LAS file per map)");
  }
  if (given("--checkpoint-every")) {
    int64_t n = 0;
    if (!ParseInt(checkpoint_every, &n) || n < 0 || n > 1000000) {
      return InvalidArgumentError("--checkpoint-every " + checkpoint_every +
                                  ": expected a number of submaps >= 0 (0 = no checkpoints)");
    }
    args.checkpoint_every_submaps = static_cast<int>(n);
  }
  if (given("--crs") && !ValidCrsText(args.crs)) {
    return InvalidArgumentError("--crs " + args.crs + ": expected EPSG:nnnn (e.g. EPSG:25832)");
  }
  if (!given("--mode")) {
    args.modes = {MappingMode::kFull, MappingMode::kGnssIns, MappingMode::kGnssInsSmoothed,
                  MappingMode::kLidarOnly};
  }
  if (args.help || args.version || args.list_config_keys) return args;
  const int inputs = !args.kitti_raw.empty() + !args.folder.empty() + !args.rosbag.empty();
  if (inputs > 1) {
    return InvalidArgumentError("--kitti-raw, --folder and --rosbag exclude each other");
  }
  if (args.rosbag.empty() &&
      !(args.lidar_topic.empty() && args.imu_topic.empty() && args.gnss_topic.empty())) {
    return InvalidArgumentError("--lidar-topic/--imu-topic/--gnss-topic go with --rosbag");
  }
  // --dump-config only writes the options: no run, so no --out needed.
  if (!args.dump_config.empty()) return args;
  if (args.out_dir.empty()) return InvalidArgumentError("--out DIR is required (see --help)");
  return args;
}

}  // namespace slam_mms::app
