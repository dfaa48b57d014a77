#pragma once
// The drive input of slam_mms_run: --kitti-raw, --folder or --rosbag (or the simulated default
// drive, a KITTI raw folder) opened as a DriveReader, and where its ground truth is looked for.

#include <filesystem>
#include <memory>

#include "slam_mms/core/status.hpp"
#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms_run/cli.hpp"

namespace slam_mms::app {

/// The path named by --kitti-raw, --folder or --rosbag; empty when none was given.
std::filesystem::path InputPath(const RunArgs& args);

/// Opens `path` as the kind the command line named (KITTI raw when none: the simulated drive),
/// with --frames, the bag topics and --extrinsics.
StatusOr<std::unique_ptr<DriveReader>> OpenRunInput(const RunArgs& args,
                                                    const std::filesystem::path& path);

/// The folder whose ground_truth/ holds a simulator's ground truth: the drive or folder itself,
/// the folder of a bag.
std::filesystem::path GroundTruthDir(const RunArgs& args, const std::filesystem::path& path);

}  // namespace slam_mms::app
