#pragma once
// Command line of slam_mms_run (issue 8: the exact interface other tools call):
//   slam_mms_run --kitti-raw DRIVE_DIR --out DIR
//                [--mode full|gnss_ins|gnss_ins_smoothed|lidar_only|all] [--pos forward|smoothed]
//                [--frames A:B] [--gnss-outage START_S:DURATION_S ...] [--config FILE]
//   slam_mms_run --out DIR      (no data: simulates the embedded default drive into DIR/sim first)
// plus --sim-duration S, --sim-seed N and --keep-sim for the simulated drive, --dump-config FILE,
// --crs EPSG:nnnn, --las-tile-size M, --resume, --checkpoint-every N, --log-level, --config-keys,
// --version and --help (RunUsage()).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/pipeline/localization_result.hpp"
#include "slam_mms/pipeline/sensor_presets.hpp"

namespace slam_mms::app {

struct RunArgs {
  std::filesystem::path kitti_raw;  ///< --kitti-raw DRIVE_DIR.
  std::filesystem::path folder;     ///< --folder DIR (plain drive folder, docs/drive_folder.md).
  std::filesystem::path rosbag;     ///< --rosbag FILE.bag (ROS 1, docs/rosbag.md).
  /// Bag topics (empty: the one topic of each message type) and --extrinsics FILE.yaml.
  std::string lidar_topic, imu_topic, gnss_topic;
  std::filesystem::path extrinsics;  ///< Empty: none (bags: identity, logged).
  /// --imu-noise FILE (io/imu_noise_yaml.hpp): the IMU's datasheet, over the input's own.
  std::filesystem::path imu_noise;
  /// --kitti-vertical-correction DEG (DriveSourceOptions::kitti_vertical_correction_deg); 0: none.
  double kitti_vertical_correction_deg = 0.0;
  /// --kitti-oxts-delay auto|SECONDS (DriveSourceOptions::kitti_oxts_inertial_delay_s); unset
  /// (auto) = estimated from the records.
  std::optional<double> kitti_oxts_inertial_delay_s;
  std::filesystem::path out_dir;
  /// In run order (all = full, gnss_ins, gnss_ins_smoothed, lidar_only).
  std::vector<MappingMode> modes;
  /// --pos: the POS `full` runs on. Forward by default: on the 190 s drive `full` on the smoothed
  /// POS was worse inside the 60 s outage (0.743 vs 0.449 m) and in ATE (0.437 vs 0.271 m).
  PosWorkflow pos = PosWorkflow::kForward;
  int64_t first_frame = 0;  ///< --frames A:B, inclusive file numbers.
  int64_t last_frame = -1;  ///< -1 = the drive's last frame.
  /// --gnss-outage windows [start_s, duration_s] relative to the first scan's start.
  std::vector<std::pair<double, double>> gnss_outages;
  std::filesystem::path config;  ///< Empty: none.
  /// --preset NAME: the LiDAR's range-image geometry (sensor_presets.hpp), before --config.
  std::optional<LidarPreset> preset;
  /// --sim-scenario: the drive simulated when no input is given (sim::DriveSimulator scenarios:
  /// "demo", about 60 s with four turns and a revisit; "default", 190 s; "long").
  std::string sim_scenario = "demo";
  double sim_duration_s = 0.0;  ///< --sim-duration: seconds of it to simulate (0 = all).
  uint64_t sim_seed = 1;
  LogLevel log_level =
      LogLevel::kWarning;  ///< --log-level: the library's messages from this level.
  bool help = false;
  bool version = false;           ///< --version: print the library version and exit.
  bool list_config_keys = false;  ///< --config-keys: print the config keys.
  /// --dump-config FILE: write the effective options (defaults + --config) as a YAML file that
  /// --config reads back unchanged, then exit.
  std::filesystem::path dump_config;
  /// --crs EPSG:nnnn: the output CRS of LAS maps and <method>_<crs>.csv trajectories (through
  /// PROJ); empty = WGS 84 / UTM zone of the world origin (EPSG 326nn/327nn).
  std::string crs;
  double las_tile_size_m = 0.0;  ///< --las-tile-size M: square LAS tiles of M metres; 0 = one file.
  bool resume = false;           ///< --resume: continue a killed run from its checkpoint in --out.
  int checkpoint_every_submaps = 10;  ///< --checkpoint-every N finished submaps (0 = never).
  bool keep_sim = false;  ///< --keep-sim: keep the simulated default drive in --out/sim.
  /// --drive-result: write the full method's DriveResult to --out/drive_result (slam_mms_merge).
  bool drive_result = false;
  /// --calibrate-extrinsics: CalibrateExtrinsics before the methods (see --help).
  bool calibrate_extrinsics = false;
  std::vector<std::string> command_line;  ///< argv as given (report.json).
};

/// Parses argv (CLI11: `--flag value` and `--flag=value`); errors name the flag and what was
/// expected (exit code 2 in main). Fills command_line with argv. With --help, --version or
/// --config-keys nothing else is required; with --dump-config no --out is required.
StatusOr<RunArgs> ParseRunArgs(int argc, const char* const* argv);

/// The --help text.
std::string RunUsage();

/// The --version line: "slam_mms_run <SLAM_MMS_VERSION_STRING>".
std::string RunVersion();

}  // namespace slam_mms::app
