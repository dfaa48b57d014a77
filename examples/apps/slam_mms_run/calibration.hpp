#pragma once
// slam_mms_run --calibrate-extrinsics (config key drive.estimate_extrinsics): the boresight
// self-calibration before the methods run, once for all of them (docs/calibration.md): the
// library's CalibrateDriveExtrinsics (the offline POS of the drive, CalibrateExtrinsics against it
// from the drive's own calibration), the
// estimate written as DIR/calib_imu_to_velo_estimated.txt (KITTI format plus lidar_time_offset_s:
// a later run takes it with --extrinsics) and as report.json's "extrinsics" object.

#include <atomic>
#include <filesystem>
#include <string>

#include "slam_mms/core/status.hpp"
#include "slam_mms/drive/extrinsic_calibrator.hpp"
#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/io/extrinsics_yaml.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"

namespace slam_mms::app {

struct RunCalibration {
  ExtrinsicCalibration result;
  DriveExtrinsics extrinsics;  ///< What the methods run with (the reader's antenna kept).
  std::string json;            ///< report.json "extrinsics".
  std::filesystem::path file;  ///< The calibration file written.
};

/// Calibrates `reader`'s extrinsic (its streams().T_body_lidar the initial value and prior) with
/// `options` (ins, origin, gnss_outages, num_threads) and `calibration`, writes the
/// file into `out_dir` and prints a summary on stdout. `input_time_offset_s`: the clock offset the
/// reader already applies (an --extrinsics file's); the file and report.json give the total
/// offset from the drive's own LiDAR stamps, RunCalibration::extrinsics the one still to apply
/// over `reader`. Errors: those of ComputeOfflinePos and CalibrateExtrinsics, kUnavailable when
/// the file cannot be written.
[[nodiscard]] StatusOr<RunCalibration> CalibrateRunExtrinsics(
    const DriveReader& reader, const MappingSystem::Options& options,
    const ExtrinsicCalibrationOptions& calibration, const std::filesystem::path& out_dir,
    double input_time_offset_s, const std::atomic<bool>* stop);

/// The "extrinsics" object of report.json for `c` and the file name written; time offsets from
/// the drive's own stamps (`input_time_offset_s` added).
std::string CalibrationJson(const ExtrinsicCalibration& c, const std::string& file_name,
                            double input_time_offset_s);

}  // namespace slam_mms::app
