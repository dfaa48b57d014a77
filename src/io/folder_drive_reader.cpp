#include "slam_mms/io/folder_drive_reader.hpp"

#include <cmath>

#include "core/option_error.hpp"
#include "io/drive_folder_parsers.hpp"
#include "io/drive_imu_noise.hpp"
#include "io/file_util.hpp"
#include "io/nmea.hpp"
#include "io/parsers.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/io/extrinsics_yaml.hpp"

namespace slam_mms {

namespace fs = std::filesystem;

namespace {

constexpr double kTimeFieldSlackS = 1.0;

// "YYYY-MM-DD" -> days since the epoch.
bool ParseDate(const std::string& s, int64_t* days) {
  if (s.size() != 10 || s[4] != '-' || s[7] != '-') return false;
  for (const size_t k : {0, 1, 2, 3, 5, 6, 8, 9}) {
    if (s[k] < '0' || s[k] > '9') return false;
  }
  const int64_t year = std::stoll(s.substr(0, 4));
  return year >= 1970 && year <= 2200 &&
         io_internal::CivilToDays(year, std::stoll(s.substr(5, 2)), std::stoll(s.substr(8, 2)),
                                  days);
}

bool Exists(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec);
}

// Keeps the records (and their sources) with stamps in [t_min, t_max].
template <typename T>
void KeepWithin(Timestamp t_min, Timestamp t_max, std::vector<T>* records,
                std::vector<std::string>* sources) {
  size_t kept = 0;
  for (size_t k = 0; k < records->size(); ++k) {
    const Timestamp t = (*records)[k].stamp;
    if (t < t_min || t > t_max) continue;
    if (kept != k) {
      (*records)[kept] = (*records)[k];
      (*sources)[kept] = std::move((*sources)[k]);
    }
    ++kept;
  }
  records->resize(kept);
  sources->resize(kept);
}

}  // namespace

Status FolderDriveReader::Options::Validate() const {
  if (first_frame < 0) {
    return internal::OptionError("FolderDriveReader::Options", "first_frame", first_frame,
                                 "must be >= 0");
  }
  if (last_frame < -1) {
    return internal::OptionError("FolderDriveReader::Options", "last_frame", last_frame,
                                 "must be >= 0 or -1 (all)");
  }
  if (last_frame >= 0 && last_frame < first_frame) {
    return InvalidArgumentError(
        "FolderDriveReader::Options::last_frame = " + std::to_string(last_frame) +
        "; must be >= first_frame = " + std::to_string(first_frame));
  }
  if (!std::isfinite(vertical_correction_deg) || std::abs(vertical_correction_deg) > 5.0) {
    return internal::OptionError("FolderDriveReader::Options", "vertical_correction_deg",
                                 vertical_correction_deg, "must be finite and within [-5, 5] deg");
  }
  if (!std::isfinite(stream_time_margin_s) || stream_time_margin_s < 0.0) {
    return internal::OptionError("FolderDriveReader::Options", "stream_time_margin_s",
                                 stream_time_margin_s, "must be >= 0");
  }
  int64_t days = 0;
  if (!nmea_utc_date.empty() && !ParseDate(nmea_utc_date, &days)) {
    return InvalidArgumentError("FolderDriveReader::Options::nmea_utc_date = '" + nmea_utc_date +
                                "'; must be a date YYYY-MM-DD (1970..2200) or empty");
  }
  return OkStatus();
}

StatusOr<std::unique_ptr<FolderDriveReader>> FolderDriveReader::Open(const fs::path& dir_in,
                                                                     const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  const fs::path dir = io_internal::DirPathWithName(dir_in);
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    return NotFoundError("drive folder " + dir.string() + " not found");
  }
  std::unique_ptr<FolderDriveReader> reader(new FolderDriveReader());
  reader->options_ = options;
  reader->dir_ = dir;

  // --- scans.csv and scans/.
  const fs::path scans_csv = dir / "scans.csv";
  if (!Exists(scans_csv)) {
    return NotFoundError(scans_csv.string() +
                         " not found (a drive folder needs scans.csv and scans/, see "
                         "docs/drive_folder.md)");
  }
  SLAM_MMS_ASSIGN_OR_RETURN(const std::string scans_bytes, io_internal::ReadFileBytes(scans_csv));
  SLAM_MMS_ASSIGN_OR_RETURN(const auto entries,
                            io_internal::ParseScansCsv(scans_bytes, scans_csv.string()));
  if (entries.empty()) return DataLossError(scans_csv.string() + ": lists no scan");
  const fs::path scans_dir = dir / "scans";
  for (const auto& e : entries) {
    const fs::path f = scans_dir / e.file;
    if (!fs::is_regular_file(f, ec)) {
      return NotFoundError(scans_csv.string() + ":" + std::to_string(e.line) + ": field 'file': " +
                           f.string() + (Exists(f) ? " is not a regular file" : " not found"));
    }
  }
  for (size_t k = 1; k < entries.size(); ++k) {
    if (entries[k].file < entries[k - 1].file) {
      SLAM_MMS_LOG(kWarning) << scans_csv.string() << ":" << entries[k].line << ": '"
                             << entries[k].file << "' sorts before '" << entries[k - 1].file
                             << "' (line " << entries[k - 1].line
                             << "): scans are read in the order of scans.csv";
      break;
    }
  }
  {
    size_t unlisted = 0;
    if (fs::is_directory(scans_dir, ec)) {
      for (const auto& entry : fs::directory_iterator(scans_dir, ec)) {
        (void)entry;
        ++unlisted;
      }
    }
    if (unlisted > entries.size()) {
      SLAM_MMS_LOG(kInfo) << scans_dir.string() << ": " << unlisted - entries.size()
                          << " entries not listed in scans.csv are ignored";
    }
  }
  const auto n = static_cast<int64_t>(entries.size());
  const int64_t first = options.first_frame;
  const int64_t last = options.last_frame < 0 ? n - 1 : options.last_frame;
  if (first >= n || last >= n) {
    return OutOfRangeError("scan range [" + std::to_string(first) + ", " +
                           std::to_string(options.last_frame) + "] outside drive folder " +
                           dir.string() + " with scans [0, " + std::to_string(n - 1) + "]");
  }
  for (int64_t k = first; k <= last; ++k) {
    const auto& e = entries[static_cast<size_t>(k)];
    reader->scans_.push_back(ScanEntry{k, scans_dir / e.file, e.start, e.end});
  }
  SLAM_MMS_RETURN_IF_ERROR(reader->LoadStreams());
  return reader;
}

Status FolderDriveReader::LoadStreams() {
  DriveStreams& s = streams_;
  const fs::path imu_csv = dir_ / "imu.csv";
  const fs::path gnss_csv = dir_ / "gnss.csv";
  const fs::path gnss_nmea = dir_ / "gnss.nmea";
  const fs::path pos_csv = dir_ / "pos.csv";
  const fs::path initial_csv = dir_ / "initial_state.csv";
  const fs::path extrinsics = dir_ / "extrinsics.yaml";

  if (Exists(pos_csv)) {
    SLAM_MMS_ASSIGN_OR_RETURN(const std::string b, io_internal::ReadFileBytes(pos_csv));
    SLAM_MMS_RETURN_IF_ERROR(io_internal::ParsePosCsv(b, pos_csv.string(), &s.pos, &s.pos_source));
  }
  if (Exists(imu_csv)) {
    SLAM_MMS_ASSIGN_OR_RETURN(const std::string b, io_internal::ReadFileBytes(imu_csv));
    SLAM_MMS_RETURN_IF_ERROR(io_internal::ParseImuCsv(b, imu_csv.string(), &s.imu, &s.imu_source));
  } else if (!Exists(pos_csv)) {
    return NotFoundError(imu_csv.string() +
                         " not found (required unless pos.csv gives an external POS)");
  } else {
    SLAM_MMS_LOG(kInfo) << dir_.string() << ": no imu.csv; the external POS pos.csv is used";
  }
  if (Exists(gnss_csv)) {
    if (Exists(gnss_nmea)) {
      SLAM_MMS_LOG(kWarning) << dir_.string()
                             << ": both gnss.csv and gnss.nmea present; gnss.csv is used";
    }
    SLAM_MMS_ASSIGN_OR_RETURN(const std::string b, io_internal::ReadFileBytes(gnss_csv));
    SLAM_MMS_RETURN_IF_ERROR(
        io_internal::ParseGnssCsv(b, gnss_csv.string(), &s.gnss, &s.gnss_source));
  } else if (Exists(gnss_nmea)) {
    io_internal::NmeaOptions nmea_options;
    if (!options_.nmea_utc_date.empty()) {
      int64_t days = 0;
      ParseDate(options_.nmea_utc_date, &days);
      nmea_options.utc_date_days = days;
    }
    SLAM_MMS_ASSIGN_OR_RETURN(const std::string b, io_internal::ReadFileBytes(gnss_nmea));
    SLAM_MMS_ASSIGN_OR_RETURN(io_internal::NmeaGnss nmea,
                              io_internal::ParseNmeaGnss(b, gnss_nmea.string(), nmea_options));
    num_bad_nmea_ = nmea.num_bad;
    for (const std::string& m : nmea.bad) SLAM_MMS_LOG(kWarning) << m << " (sentence skipped)";
    if (nmea.num_bad > nmea.bad.size()) {
      SLAM_MMS_LOG(kWarning) << gnss_nmea.string() << ": " << nmea.num_bad - nmea.bad.size()
                             << " more bad sentences skipped";
    }
    if (nmea.num_without_gst > 0) {
      SLAM_MMS_LOG(kInfo) << gnss_nmea.string() << ": " << nmea.num_without_gst << " of "
                          << nmea.fixes.size()
                          << " fixes have no GST sentence; their sigmas are defaults by fix type";
    }
    if (nmea.num_empty_separation > 0) {
      SLAM_MMS_LOG(kInfo) << gnss_nmea.string() << ": " << nmea.num_empty_separation
                          << " GGA sentences without geoid separation (taken as 0)";
    }
    s.gnss = std::move(nmea.fixes);
    for (const int line : nmea.fix_lines) {
      s.gnss_source.push_back(gnss_nmea.string() + ":" + std::to_string(line));
    }
  } else {
    SLAM_MMS_LOG(kInfo) << dir_.string() << ": no gnss.csv or gnss.nmea; a drive without GNSS";
  }
  if (Exists(initial_csv)) {
    SLAM_MMS_ASSIGN_OR_RETURN(const std::string b, io_internal::ReadFileBytes(initial_csv));
    SLAM_MMS_RETURN_IF_ERROR(io_internal::ParseInitialStateCsv(
        b, initial_csv.string(), &s.initial_state, &s.initial_state_source,
        &s.initial_attitude_sigma_rpy_rad));
  }
  SLAM_MMS_RETURN_IF_ERROR(io_internal::ReadDriveImuNoise(dir_, &s));
  if (Exists(extrinsics)) {
    SLAM_MMS_ASSIGN_OR_RETURN(const DriveExtrinsics e, ReadExtrinsicsYaml(extrinsics));
    s.T_body_lidar = e.T_body_lidar;
    s.t_body_antenna_m = e.t_body_antenna_m;
    s.imu_frame_is_vehicle_frame = e.imu_frame_is_vehicle_frame.value_or(false);
  } else if (options_.allow_missing_extrinsics) {
    SLAM_MMS_LOG(kWarning) << extrinsics.string() << " not found; using identity T_body_lidar";
  } else {
    return NotFoundError(extrinsics.string() +
                         " not found (T_body_lidar is needed; "
                         "FolderDriveReader::Options::allow_missing_extrinsics gives identity)");
  }
  const Timestamp t_min = scans_.front().start.PlusSeconds(-options_.stream_time_margin_s);
  const Timestamp t_max = scans_.back().end.PlusSeconds(options_.stream_time_margin_s);
  KeepWithin(t_min, t_max, &s.imu, &s.imu_source);
  KeepWithin(t_min, t_max, &s.gnss, &s.gnss_source);
  KeepWithin(t_min, t_max, &s.pos, &s.pos_source);
  return OkStatus();
}

std::string FolderDriveReader::Describe() const { return "folder " + dir_.string(); }

std::string FolderDriveReader::ScanSource(size_t i) const { return scans_.at(i).file.string(); }

StatusOr<Scan> FolderDriveReader::ReadScan(size_t i) const {
  if (i >= scans_.size()) {
    return OutOfRangeError("FolderDriveReader::ReadScan(" + std::to_string(i) + "): only " +
                           std::to_string(scans_.size()) + " scans");
  }
  const ScanEntry& e = scans_[i];
  const std::string f = e.file.string();
  io_internal::ScanFileKind kind;
  io_internal::ScanFileKindOf(f, &kind);
  SLAM_MMS_ASSIGN_OR_RETURN(const std::string bytes, io_internal::ReadFileBytes(e.file));
  io_internal::ScanFilePoints raw;
  SLAM_MMS_RETURN_IF_ERROR(io_internal::ParseScanFile(bytes, kind, f, &raw));
  const size_t n = raw.xyzr.size() / 4;
  if (n == 0) return DataLossError(f + ": scan contains no points");

  Scan scan;
  scan.index = e.index;
  scan.stamp_start = e.start;
  scan.stamp_end = e.end;
  scan.stamp_trigger = Timestamp::FromNanoseconds(
      e.start.nanoseconds() + (e.end.nanoseconds() - e.start.nanoseconds()) / 2);
  scan.source = f;
  const double duration_s = e.end.SecondsSince(e.start);
  const bool with_time = !raw.time_field.empty();
  if (with_time && options_.per_point_time) {
    for (size_t k = 0; k < n; ++k) {
      const float t = raw.time_s[k];
      if (std::isfinite(t) && (t < -kTimeFieldSlackS || t > duration_s + kTimeFieldSlackS)) {
        return DataLossError(f + ": point " + std::to_string(k) + " field '" + raw.time_field +
                             "' = " + std::to_string(t) + " is outside the scan (duration " +
                             std::to_string(duration_s) +
                             " s); the time field must be seconds from the scan start");
      }
    }
  }
  KittiRawReader::Options o;
  o.spin = options_.spin;
  o.per_point_time = options_.per_point_time;
  o.vertical_angle_correction = options_.vertical_angle_correction;
  o.vertical_correction_deg = options_.vertical_correction_deg;
  const size_t dropped = io_internal::KittiPointsToCloud(raw.xyzr, o, duration_s, &scan.cloud,
                                                         with_time ? &raw.time_s : nullptr);
  if (dropped > 0) {
    dropped_ += dropped;
    SLAM_MMS_LOG(kWarning) << f << ": dropped " << dropped << " of " << n
                           << " points with NaN/Inf values";
  }
  if (scan.cloud.empty()) {
    return DataLossError(f + ": scan has no finite point (" + std::to_string(n) +
                         " points, all NaN/Inf)");
  }
  return scan;
}

}  // namespace slam_mms
