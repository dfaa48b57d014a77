#pragma once
// Private parse-from-memory entry points of the io module. The file readers (KittiRawReader,
// ReadKittiScanFile, ReadKittiRigidCalibration, ReadKittiImuToVelo, Read*Trajectory*) read a file's
// bytes and call these, so the libFuzzer targets in fuzz/ and the tests exercise exactly the code
// the readers run. `file` only names the source in error messages ("<file>:<line>: ...").
//
// Thread safety: pure functions; safe from any thread.

#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/io/extrinsics_yaml.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/io/oxts_record.hpp"

namespace slam_mms::io_internal {

/// A .bin or .txt KITTI scan file into x y z reflectance quadruples (non-finite values kept).
Status ReadKittiRawScan(const std::filesystem::path& file, std::vector<float>* xyzr);

/// A KITTI .bin scan (float32 x y z reflectance, little endian) into `xyzr` (non-finite values
/// kept). kDataLoss when the size is not a multiple of 16.
Status ParseKittiBinScan(std::string_view bytes, const std::string& file, std::vector<float>* xyzr);

/// A KITTI extract .txt scan ("x y z reflectance" per line, blank lines skipped) into `xyzr`.
Status ParseKittiTextScan(const std::vector<std::string>& lines, const std::string& file,
                          std::vector<float>* xyzr);

/// Turns raw x y z reflectance quadruples into `cloud` as KittiRawReader::ReadScan does: drops
/// non-finite points, applies the vertical-angle correction and the azimuth time of `options` over
/// a scan of `duration_s`. Returns the number of points dropped. Where `time_offsets_s` is given
/// (one per point: a drive folder scan's own time field), it replaces the azimuth time when
/// options.per_point_time, and a point whose time is not finite is dropped too.
size_t KittiPointsToCloud(const std::vector<float>& xyzr, const KittiRawReader::Options& options,
                          double duration_s, PointCloud* cloud,
                          const std::vector<float>* time_offsets_s = nullptr);

/// One oxts/data/NNNNNNNNNN.txt file: exactly one non-blank line, parsed by ParseOxtsLine.
StatusOr<OxtsRecord> ParseOxtsFileLines(const std::vector<std::string>& lines,
                                        const std::string& file);

/// A KITTI "R: 9 numbers / T: 3 numbers" calibration file (see ReadKittiRigidCalibration).
StatusOr<Eigen::Isometry3d> ParseKittiRigidCalibrationLines(const std::vector<std::string>& lines,
                                                            const std::string& file);

/// ReadKittiImuToVelo (kitti_calibration.hpp) on lines already in memory.
StatusOr<DriveExtrinsics> ParseKittiImuToVeloLines(const std::vector<std::string>& lines,
                                                   const std::string& file);

/// The trajectory readers of trajectory_io.hpp on lines already in memory.
StatusOr<Trajectory> ParseTrajectoryTumLines(const std::vector<std::string>& lines,
                                             const std::string& file);
StatusOr<std::vector<Eigen::Isometry3d>> ParsePosesKittiLines(const std::vector<std::string>& lines,
                                                              const std::string& file);
StatusOr<Trajectory> ParseTrajectoryCsvLines(const std::vector<std::string>& lines,
                                             const std::string& file);

}  // namespace slam_mms::io_internal
