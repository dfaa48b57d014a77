#include "slam_mms/io/drive_folder_writer.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>

#include "io/drive_folder_parsers.hpp"
#include "io/file_util.hpp"
#include "io/nmea.hpp"
#include "slam_mms/io/extrinsics_yaml.hpp"
#include "slam_mms/io/imu_noise_yaml.hpp"
#include "slam_mms/io/oxts_record.hpp"

namespace slam_mms {

namespace fs = std::filesystem;
using io_internal::CsvLine;
using io_internal::FormatDouble;

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

std::string Header(const io_internal::CsvSchema& schema, size_t num_optional) {
  std::vector<std::string> names = schema.required;
  names.insert(names.end(), schema.optional.begin(),
               schema.optional.begin() + static_cast<std::ptrdiff_t>(num_optional));
  return CsvLine(names);
}

std::string Ns(Timestamp t) { return std::to_string(t.nanoseconds()); }

// Roll, pitch, yaw [deg] of R = Rz(yaw) Ry(pitch) Rx(roll) (SetOxtsAttitude).
void RpyDeg(const Eigen::Matrix3d& R, double rpy[3]) {
  OxtsRecord r;
  SetOxtsAttitude(R, &r);
  rpy[0] = r.roll_rad * kRadToDeg;
  rpy[1] = r.pitch_rad * kRadToDeg;
  rpy[2] = r.yaw_rad * kRadToDeg;
}

const char* Extension(FolderWriteOptions::ScanFormat f) {
  switch (f) {
    case FolderWriteOptions::ScanFormat::kPcdBinary:
    case FolderWriteOptions::ScanFormat::kPcdAscii: return ".pcd";
    case FolderWriteOptions::ScanFormat::kPlyBinary:
    case FolderWriteOptions::ScanFormat::kPlyAscii: return ".ply";
    default: return ".bin";
  }
}

Status WriteScans(const DriveReader& reader, const fs::path& dir, const FolderWriteOptions& o) {
  const fs::path scans_dir = dir / "scans";
  std::error_code ec;
  fs::create_directories(scans_dir, ec);
  if (ec) return UnavailableError("cannot create " + scans_dir.string() + ": " + ec.message());
  io_internal::ScanFileKind kind;
  io_internal::ScanFileKindOf(std::string("x") + Extension(o.scan_format), &kind);
  const bool ascii = o.scan_format == FolderWriteOptions::ScanFormat::kPcdAscii ||
                     o.scan_format == FolderWriteOptions::ScanFormat::kPlyAscii;
  std::string csv = Header(io_internal::ScansCsvSchema(), 0);
  for (size_t i = 0; i < reader.NumScans(); ++i) {
    auto scan = reader.ReadScan(i);
    if (!scan.ok()) return scan.status().WithContext("WriteDriveFolder: " + reader.ScanSource(i));
    char name[40];
    std::snprintf(name, sizeof(name), "%010zu%s", i, Extension(o.scan_format));
    SLAM_MMS_RETURN_IF_ERROR(io_internal::WriteFileBytes(
        scans_dir / name,
        io_internal::FormatScanFile(scan->cloud, kind, ascii, o.write_point_time)));
    csv += CsvLine({name, Ns(reader.ScanStart(i)), Ns(reader.ScanEnd(i))});
  }
  return io_internal::WriteFileBytes(dir / "scans.csv", csv);
}

Status WriteStreams(const DriveStreams& s, const fs::path& dir, const FolderWriteOptions& o) {
  std::string imu = Header(io_internal::ImuCsvSchema(), 0);
  for (const ImuSample& m : s.imu) {
    imu += CsvLine({Ns(m.stamp), FormatDouble(m.accel_mps2.x()), FormatDouble(m.accel_mps2.y()),
                    FormatDouble(m.accel_mps2.z()), FormatDouble(m.gyro_radps.x()),
                    FormatDouble(m.gyro_radps.y()), FormatDouble(m.gyro_radps.z())});
  }
  SLAM_MMS_RETURN_IF_ERROR(io_internal::WriteFileBytes(dir / "imu.csv", imu));

  if (!s.gnss.empty() && o.gnss_format == FolderWriteOptions::GnssFormat::kCsv) {
    std::string gnss = Header(io_internal::GnssCsvSchema(), 1);
    for (const GnssFix& f : s.gnss) {
      const std::string h = FormatDouble(f.sigma_horizontal_m);
      gnss += CsvLine({Ns(f.stamp), FormatDouble(f.latitude_deg), FormatDouble(f.longitude_deg),
                       FormatDouble(f.height_m), h, h, FormatDouble(f.sigma_vertical_m),
                       io_internal::GnssFixCsvName(f.type), std::to_string(f.num_satellites)});
    }
    SLAM_MMS_RETURN_IF_ERROR(io_internal::WriteFileBytes(dir / "gnss.csv", gnss));
  } else if (!s.gnss.empty()) {
    std::string nmea;
    for (const GnssFix& f : s.gnss) nmea += io_internal::FormatNmeaEpoch(f, o.nmea_time_decimals);
    SLAM_MMS_RETURN_IF_ERROR(io_internal::WriteFileBytes(dir / "gnss.nmea", nmea));
  }

  DriveExtrinsics e;
  e.T_body_lidar = s.T_body_lidar;
  e.t_body_antenna_m = s.t_body_antenna_m;
  if (s.imu_frame_is_vehicle_frame) e.imu_frame_is_vehicle_frame = true;
  SLAM_MMS_RETURN_IF_ERROR(WriteExtrinsicsYaml(e, dir / "extrinsics.yaml"));
  if (s.imu_noise) {
    SLAM_MMS_RETURN_IF_ERROR(WriteImuNoiseYaml(*s.imu_noise, dir / kImuNoiseFileName));
  }

  if (s.initial_state) {
    const InsState& x = *s.initial_state;
    double rpy[3];
    RpyDeg(x.T_world_body.linear(), rpy);
    std::vector<std::string> row = {Ns(x.stamp),
                                    FormatDouble(rpy[0]),
                                    FormatDouble(rpy[1]),
                                    FormatDouble(rpy[2]),
                                    FormatDouble(x.v_world_mps.x()),
                                    FormatDouble(x.v_world_mps.y()),
                                    FormatDouble(x.v_world_mps.z())};
    const std::optional<Eigen::Vector3d>& sigma = s.initial_attitude_sigma_rpy_rad;
    if (sigma) {
      for (int k = 0; k < 3; ++k) row.push_back(FormatDouble((*sigma)[k] * kRadToDeg));
    }
    const std::string text =
        Header(io_internal::InitialStateCsvSchema(), sigma ? 3 : 0) + CsvLine(row);
    SLAM_MMS_RETURN_IF_ERROR(io_internal::WriteFileBytes(dir / "initial_state.csv", text));
  }

  if (!s.pos.empty()) {
    // Sigma groups only where every record has them (the CSV has one header).
    bool rpy_sigmas = true, enu_sigmas = true;
    for (const PosRecord& p : s.pos) {
      rpy_sigmas = rpy_sigmas && p.sigma_rpy_rad.has_value();
      enu_sigmas = enu_sigmas && p.sigma_enu_m.has_value();
    }
    std::vector<std::string> names = io_internal::PosCsvSchema().required;
    const auto& opt = io_internal::PosCsvSchema().optional;
    if (rpy_sigmas) names.insert(names.end(), opt.begin(), opt.begin() + 3);
    if (enu_sigmas) names.insert(names.end(), opt.begin() + 3, opt.end());
    std::string text = CsvLine(names);
    for (const PosRecord& p : s.pos) {
      double rpy[3];
      RpyDeg(p.R_enu_body, rpy);
      std::vector<std::string> row = {Ns(p.stamp),
                                      FormatDouble(p.latitude_deg),
                                      FormatDouble(p.longitude_deg),
                                      FormatDouble(p.height_m),
                                      FormatDouble(rpy[0]),
                                      FormatDouble(rpy[1]),
                                      FormatDouble(rpy[2])};
      if (rpy_sigmas) {
        for (int k = 0; k < 3; ++k) row.push_back(FormatDouble((*p.sigma_rpy_rad)[k] * kRadToDeg));
      }
      if (enu_sigmas) {
        for (int k = 0; k < 3; ++k) row.push_back(FormatDouble((*p.sigma_enu_m)[k]));
      }
      text += CsvLine(row);
    }
    SLAM_MMS_RETURN_IF_ERROR(io_internal::WriteFileBytes(dir / "pos.csv", text));
  }
  return OkStatus();
}

}  // namespace

Status FolderWriteOptions::Validate() const {
  if (write_point_time && scan_format == ScanFormat::kBin) {
    return InvalidArgumentError(
        "FolderWriteOptions::write_point_time = true with scan_format kBin; KITTI .bin scans have "
        "no time field (use a PCD or PLY format)");
  }
  if (nmea_time_decimals < 0 || nmea_time_decimals > 9) {
    return InvalidArgumentError("FolderWriteOptions::nmea_time_decimals = " +
                                std::to_string(nmea_time_decimals) + "; must be in [0, 9]");
  }
  return OkStatus();
}

Status WriteDriveFolder(const DriveReader& reader, const fs::path& dir_in,
                        const FolderWriteOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  const fs::path dir = io_internal::DirPathWithName(dir_in);
  if (dir.empty()) return InvalidArgumentError("WriteDriveFolder: empty folder path");
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_empty(dir, ec)) {
    if (!options.overwrite) {
      return InvalidArgumentError("WriteDriveFolder: " + dir.string() +
                                  " exists and is not empty (set FolderWriteOptions::overwrite)");
    }
    fs::remove_all(dir, ec);
    if (ec) return UnavailableError("cannot remove " + dir.string() + ": " + ec.message());
  }
  fs::create_directories(dir, ec);
  if (ec) return UnavailableError("cannot create " + dir.string() + ": " + ec.message());
  SLAM_MMS_RETURN_IF_ERROR(WriteScans(reader, dir, options));
  return WriteStreams(reader.streams(), dir, options);
}

}  // namespace slam_mms
