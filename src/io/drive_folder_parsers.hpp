#pragma once
// Private parse-from-memory entry points of the drive folder (FolderDriveReader, WriteDriveFolder),
// as src/io/parsers.hpp for KITTI: the reader reads each file's bytes and calls these, so the fuzz
// targets fuzz/fuzz_pcd.cpp and fuzz/fuzz_csv.cpp (and fuzz_nmea.cpp through nmea.hpp) run exactly
// the reader's code. `file` only names the source in messages ("<file>:<line>: field 'name'").
// The column names of each CSV file are here too, shared by the reader and the writer.
//
// Thread safety: pure functions; safe from any thread.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/csv_table.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms::io_internal {

// ---- CSV files -----------------------------------------------------------------------------
const CsvSchema& ScansCsvSchema();         ///< file,stamp_start_ns,stamp_end_ns
const CsvSchema& ImuCsvSchema();           ///< stamp_ns,ax,ay,az,wx,wy,wz
const CsvSchema& GnssCsvSchema();          ///< stamp_ns,lat_deg,...,fix [,num_sats]
const CsvSchema& InitialStateCsvSchema();  ///< stamp_ns,roll_deg,...,v_up_mps
const CsvSchema& PosCsvSchema();           ///< stamp_ns,lat_deg,...,yaw_deg [,sigmas]

/// One row of scans.csv.
struct FolderScanEntry {
  std::string file;  ///< Relative to DIR/scans/.
  Timestamp start, end;
  int line = 0;
};

/// scans.csv: names relative (no "..", not absolute) and unique, start strictly increasing, end
/// after start.
StatusOr<std::vector<FolderScanEntry>> ParseScansCsv(std::string_view bytes,
                                                     const std::string& file);
/// imu.csv; `sources` gets "file:line" per sample.
Status ParseImuCsv(std::string_view bytes, const std::string& file, std::vector<ImuSample>* imu,
                   std::vector<std::string>* sources);
/// gnss.csv (fix names none, sps, dgps, float, fixed; sigma_horizontal = sigma_e if equal to
/// sigma_n, else sqrt((e^2 + n^2) / 2); sigma_vertical = sigma_u).
Status ParseGnssCsv(std::string_view bytes, const std::string& file, std::vector<GnssFix>* gnss,
                    std::vector<std::string>* sources);
/// initial_state.csv: the first data row (none: `state` left empty); the optional
/// sigma_roll_deg, sigma_pitch_deg, sigma_yaw_deg group (all three or none) into `sigma_rpy_rad`.
Status ParseInitialStateCsv(std::string_view bytes, const std::string& file,
                            std::optional<InsState>* state, std::string* source,
                            std::optional<Eigen::Vector3d>* sigma_rpy_rad);
/// pos.csv (optional sigma columns in groups of three).
Status ParsePosCsv(std::string_view bytes, const std::string& file, std::vector<PosRecord>* pos,
                   std::vector<std::string>* sources);

/// Fix type <-> its gnss.csv name.
const char* GnssFixCsvName(GnssFixType type);
bool ParseGnssFixCsvName(const std::string& name, GnssFixType* type);

// ---- Scan files ----------------------------------------------------------------------------
enum class ScanFileKind { kPcd, kPly, kKittiBin };

/// The kind from the file name's extension (.pcd, .ply, .bin; any case); false when unknown.
bool ScanFileKindOf(const std::string& name, ScanFileKind* kind);

/// The raw points of a scan file: x y z intensity quadruples (intensity 0 where the file has none;
/// non-finite values kept) and, where the file has a time field (t, time or timestamp, in this
/// preference), one time [s from the scan start] per point.
struct ScanFilePoints {
  std::vector<float> xyzr;
  std::vector<float> time_s;
  std::string time_field;  ///< "" when none.
  size_t declared_points = 0;
};

/// PCD / PLY (point_file_format.hpp) or KITTI .bin (float32 x y z reflectance). The file needs
/// fields x, y and z; intensity may be called intensity, reflectance or scalar_intensity.
Status ParseScanFile(std::string_view bytes, ScanFileKind kind, const std::string& file,
                     ScanFilePoints* points);

/// A scan file's bytes as WriteDriveFolder writes them: float32 x y z intensity [t], PCD v0.7
/// (DATA binary or ascii), PLY (binary_little_endian or ascii), or KITTI .bin (no time).
std::string FormatScanFile(const PointCloud& cloud, ScanFileKind kind, bool ascii, bool with_time);

}  // namespace slam_mms::io_internal
