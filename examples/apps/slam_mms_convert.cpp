// slam_mms_convert: rewrites a drive from one input format into another, so that every drive the
// tests and users have (KITTI raw, simulated drives) is also a plain-folder and a ROS-bag drive.
//
//   slam_mms_convert (--kitti-raw DIR | --folder DIR | --rosbag FILE.bag) [--frames A:B]
//                    [--extrinsics FILE.yaml] [--lidar-topic T --imu-topic T --gnss-topic T]
//                    --to folder|rosbag|kitti-raw --out PATH
//                    [--scan-format pcd_binary|pcd_ascii|ply_binary|ply_ascii|bin]
//                    [--gnss csv|nmea] [--point-time] [--no-point-time]
//
// --to folder: PATH is the folder (docs/drive_folder.md); --to rosbag: PATH is FILE.bag
// (docs/rosbag.md); --to kitti-raw: PATH is the drive folder .../<date>_drive_<n>_sync
// (calibration in its parent). A simulator's ground_truth/ folder next to the input (inside a
// drive or plain folder, beside a bag) is copied to the same place next to the output, so
// slam_mms_run evaluates the converted drive against the same truth.
// Exit status: 0 done, 1 input or write error (message names file/line/field), 2 bad command line.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/drive/open_drive.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/version.hpp"
#include "slam_mms_convert/writers.hpp"

namespace fs = std::filesystem;
using namespace slam_mms;  // NOLINT(google-build-using-namespace)

namespace {

int Fail(const Status& status) {
  std::fprintf(stderr, "slam_mms_convert: error: %s\n", status.ToString().c_str());
  return 1;
}

// ground_truth/ of the input (inside a folder, beside a bag) copied to the output's place.
Status CopyGroundTruth(const fs::path& input, bool input_is_bag, const fs::path& output,
                       bool output_is_bag) {
  const fs::path from = (input_is_bag ? input.parent_path() : input) / "ground_truth";
  std::error_code ec;
  if (!fs::is_directory(from, ec)) return OkStatus();
  const fs::path to = (output_is_bag ? output.parent_path() : output) / "ground_truth";
  fs::create_directories(to, ec);
  fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing, ec);
  if (ec)
    return InternalError("copying " + from.string() + " to " + to.string() + ": " + ec.message());
  std::printf("[convert] ground truth copied to %s\n", to.c_str());
  return OkStatus();
}

}  // namespace

int main(int argc, char** argv) {
  SetLogSink(StderrLogSink());
  SetMinLogLevel(LogLevel::kWarning);
  CLI::App app{
      "slam_mms_convert: a drive from one input format into another (KITTI raw, plain "
      "drive folder, ROS 1 bag)"};
  app.set_version_flag("--version", std::string("slam_mms_convert ") + SLAM_MMS_VERSION_STRING);
  std::string kitti_raw, folder, rosbag, extrinsics, frames, to, out;
  DriveSourceOptions in;
  app.add_option("--kitti-raw", kitti_raw, "KITTI raw drive folder");
  app.add_option("--folder", folder, "plain drive folder (docs/drive_folder.md)");
  app.add_option("--rosbag", rosbag, "ROS 1 bag (docs/rosbag.md)");
  app.add_option("--frames", frames, "only scans A..B (inclusive; KITTI file numbers)");
  app.add_option("--extrinsics", extrinsics,
                 "extrinsics.yaml for a bag (or to override a folder's)");
  app.add_option("--lidar-topic", in.lidar_topic, "bag topic of the PointCloud2 scans");
  app.add_option("--imu-topic", in.imu_topic, "bag topic of the sensor_msgs/Imu samples");
  app.add_option("--gnss-topic", in.gnss_topic, "bag topic of the sensor_msgs/NavSatFix fixes");
  app.add_option("--to", to, "output format")
      ->required()
      ->check(CLI::IsMember({"folder", "rosbag", "kitti-raw"}));
  app.add_option("--out", out, "output folder (folder, kitti-raw) or FILE.bag (rosbag)")
      ->required();
  app::WriteSettings settings;
  app.add_option("--scan-format", settings.scan_format, "scan files of --to folder")
      ->check(CLI::IsMember(app::ScanFormatNames()));
  app.add_option("--gnss", settings.gnss_format, "GNSS file of --to folder")
      ->check(CLI::IsMember({"csv", "nmea"}));
  app.add_flag("--point-time", settings.folder_point_time,
               "--to folder: store per-point times as a float32 `t` field in PCD/PLY (default: "
               "none, the reader derives them from the azimuth and scans.csv's start/end)");
  app.add_flag("--no-point-time", settings.bag_no_point_time,
               "--to rosbag: leave out PointCloud2's `time` field (as kitti2bag); the reader then "
               "derives times from the azimuth over the median scan period");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help / --version: exit 0 (CLI11 prints them); a bad command line: exit 2 (as documented).
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  const int inputs = !kitti_raw.empty() + !folder.empty() + !rosbag.empty();
  if (inputs != 1) {
    std::fprintf(stderr, "slam_mms_convert: give exactly one of --kitti-raw, --folder, --rosbag\n");
    return 2;
  }
  if (!frames.empty()) {
    long long a = 0, b = 0;
    char tail = 0;
    if (std::sscanf(frames.c_str(), "%lld:%lld%c", &a, &b, &tail) != 2 || a < 0 || b < a) {
      std::fprintf(stderr, "slam_mms_convert: --frames %s: expected A:B with 0 <= A <= B\n",
                   frames.c_str());
      return 2;
    }
    in.first_frame = a;
    in.last_frame = b;
  }
  in.kind = !folder.empty()   ? DriveSourceKind::kFolder
            : !rosbag.empty() ? DriveSourceKind::kRosbag
                              : DriveSourceKind::kKittiRaw;
  in.extrinsics = extrinsics;
  const fs::path input = !folder.empty() ? folder : !rosbag.empty() ? rosbag : kitti_raw;
  StatusOr<std::unique_ptr<DriveReader>> reader = OpenDrive(input, in);
  if (!reader.ok()) return Fail(reader.status());
  std::printf("[convert] %s: %zu scans, %zu IMU samples, %zu GNSS fixes -> %s %s\n",
              (*reader)->Describe().c_str(), (*reader)->NumScans(), (*reader)->streams().imu.size(),
              (*reader)->streams().gnss.size(), to.c_str(), out.c_str());
  std::fflush(stdout);

  if (to == "rosbag" && fs::path(out).has_parent_path()) {
    std::error_code ec;
    fs::create_directories(fs::path(out).parent_path(), ec);
    if (ec) return Fail(InvalidArgumentError("--out " + out + ": " + ec.message()));
  }
  const Status written = app::WriteDrive(**reader, to, out, settings);
  if (!written.ok()) return Fail(written);
  const Status gt = CopyGroundTruth(input, !rosbag.empty(), out, to == "rosbag");
  if (!gt.ok()) return Fail(gt);
  if ((*reader)->TotalDroppedPoints() > 0) {
    std::printf("[convert] %llu non-finite points dropped\n",
                static_cast<unsigned long long>((*reader)->TotalDroppedPoints()));
  }
  std::printf("[convert] done: %s\n", out.c_str());
  return 0;
}
