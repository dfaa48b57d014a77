#include "slam_mms/io/kitti_raw_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "core/option_error.hpp"
#include "io/file_util.hpp"
#include "io/parsers.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

namespace fs = std::filesystem;
using io_internal::ReadLines;
using io_internal::ReadTimestampFile;

namespace {

constexpr int kKittiNameDigits = 10;

// "0000000012.bin" -> 12; -1 when the stem is not 10 digits.
int64_t FileNumber(const fs::path& file) {
  const std::string stem = file.stem().string();
  if (stem.size() != kKittiNameDigits) return -1;
  int64_t v = 0;
  for (const char c : stem) {
    if (c < '0' || c > '9') return -1;
    v = v * 10 + (c - '0');
  }
  return v;
}

// Numbered files of `dir` with extension `ext` (".bin"/".txt"; "" = any), by number.
StatusOr<std::map<int64_t, fs::path>> ListNumberedFiles(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return NotFoundError("folder " + dir.string() + " not found");
  std::map<int64_t, fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    const int64_t n = FileNumber(entry.path());
    if (n < 0) continue;
    if (files.count(n) != 0) {
      return DataLossError("two files numbered " + std::to_string(n) + " in " + dir.string() +
                           ": " + files[n].filename().string() + " and " +
                           entry.path().filename().string());
    }
    files[n] = entry.path();
  }
  if (ec) return DataLossError("cannot list " + dir.string() + ": " + ec.message());
  return files;
}

StatusOr<OxtsRecord> ReadOxtsFile(const fs::path& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const std::vector<std::string> lines, ReadLines(file));
  return io_internal::ParseOxtsFileLines(lines, file.string());
}

}  // namespace

StatusOr<OxtsRecord> io_internal::ParseOxtsFileLines(const std::vector<std::string>& lines,
                                                     const std::string& file) {
  int record_line = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (io_internal::IsBlank(lines[i])) continue;
    if (record_line != 0) {
      return DataLossError(file + ":" + std::to_string(i + 1) +
                           ": more than one OXTS record in the file (first on line " +
                           std::to_string(record_line) + ")");
    }
    record_line = static_cast<int>(i) + 1;
  }
  if (record_line == 0) return DataLossError(file + ":1: empty OXTS file");
  return ParseOxtsLine(lines[record_line - 1], file, record_line);
}

namespace {

// Reads an OXTS folder (`dir`/timestamps.txt + `dir`/data/NNNNNNNNNN.txt). Records whose file
// number is in [first, last] (sync) or whose stamp is in [t_min, t_max] (other) are kept.
struct OxtsSelection {
  bool by_index = true;
  int64_t first = 0;
  int64_t last = -1;
  Timestamp t_min;
  Timestamp t_max;
};

StatusOr<std::vector<StampedOxts>> ReadOxtsFolder(const fs::path& dir, bool allow_blank_lines,
                                                  const OxtsSelection& sel, size_t* num_lines_out) {
  SLAM_MMS_ASSIGN_OR_RETURN(const auto stamps,
                            ReadTimestampFile(dir / "timestamps.txt", allow_blank_lines));
  SLAM_MMS_ASSIGN_OR_RETURN(const auto files, ListNumberedFiles(dir / "data"));
  *num_lines_out = stamps.size();
  if (!files.empty() && files.rbegin()->first >= static_cast<int64_t>(stamps.size())) {
    return DataLossError((dir / "data" / files.rbegin()->second.filename()).string() +
                         ": no line for it in " + (dir / "timestamps.txt").string() + " (" +
                         std::to_string(stamps.size()) + " lines)");
  }
  std::vector<StampedOxts> records;
  size_t lost = 0;
  for (size_t i = 0; i < stamps.size(); ++i) {
    const auto n = static_cast<int64_t>(i);
    if (sel.by_index && (n < sel.first || n > sel.last)) continue;
    if (!stamps[i].has_value()) {
      ++lost;
      continue;
    }
    if (!sel.by_index && (*stamps[i] < sel.t_min || *stamps[i] > sel.t_max)) continue;
    const auto it = files.find(n);
    if (it == files.end()) {
      return NotFoundError((dir / "data").string() + ": OXTS file " + std::to_string(n) +
                           " missing (timestamps.txt line " + std::to_string(i + 1) + " has " +
                           stamps[i]->ToKittiString() + ")");
    }
    SLAM_MMS_ASSIGN_OR_RETURN(OxtsRecord record, ReadOxtsFile(it->second));
    records.push_back(StampedOxts{*stamps[i], n, record});
  }
  if (lost > 0) {
    SLAM_MMS_LOG(kInfo) << dir.string() << ": " << lost
                        << " OXTS records lost (empty timestamp lines) skipped";
  }
  return records;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
Status KittiRawReader::Options::Validate() const {
  if (first_frame < 0) {
    return internal::OptionError("KittiRawReader::Options", "first_frame", first_frame,
                                 "must be >= 0");
  }
  if (last_frame < -1) {
    return internal::OptionError("KittiRawReader::Options", "last_frame", last_frame,
                                 "must be >= 0 or -1 (all)");
  }
  if (last_frame >= 0 && last_frame < first_frame) {
    return InvalidArgumentError(
        "KittiRawReader::Options::last_frame = " + std::to_string(last_frame) +
        "; must be >= first_frame = " + std::to_string(first_frame));
  }
  if (!std::isfinite(vertical_correction_deg) || std::abs(vertical_correction_deg) > 5.0) {
    return internal::OptionError("KittiRawReader::Options", "vertical_correction_deg",
                                 vertical_correction_deg, "must be finite and within [-5, 5] deg");
  }
  if (oxts_inertial_delay_s &&
      (!std::isfinite(*oxts_inertial_delay_s) || std::abs(*oxts_inertial_delay_s) > 0.5)) {
    return internal::OptionError("KittiRawReader::Options", "oxts_inertial_delay_s",
                                 *oxts_inertial_delay_s, "must be finite and within [-0.5, 0.5] s");
  }
  if (!std::isfinite(imu_time_margin_s) || imu_time_margin_s < 0.0) {
    return internal::OptionError("KittiRawReader::Options", "imu_time_margin_s", imu_time_margin_s,
                                 "must be >= 0");
  }
  return OkStatus();
}

struct KittiRawReader::Impl {
  Options options;
  fs::path drive_dir;
  KittiRawLayout layout = KittiRawLayout::kSync;
  struct Frame {
    int64_t index;
    fs::path file;
    Timestamp start, end, trigger;
  };
  std::vector<Frame> frames;
  std::vector<StampedOxts> oxts;
  std::vector<StampedOxts> imu_oxts;
  bool has_imu_100hz = false;
  double oxts_inertial_delay_s = 0.0;
  std::optional<OxtsInertialDelay> oxts_inertial_delay_estimate;
  Eigen::Isometry3d T_lidar_body = Eigen::Isometry3d::Identity();
  fs::path calibration_file;
  mutable std::atomic<uint64_t> dropped{0};
};

KittiRawReader::KittiRawReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
KittiRawReader::KittiRawReader(KittiRawReader&&) noexcept = default;
KittiRawReader& KittiRawReader::operator=(KittiRawReader&&) noexcept = default;
KittiRawReader::~KittiRawReader() = default;

StatusOr<KittiRawReader> KittiRawReader::Open(const fs::path& drive_dir) {
  return Open(drive_dir, Options());
}

StatusOr<KittiRawReader> KittiRawReader::Open(const fs::path& drive_dir_in,
                                              const Options& options) {
  // "a/drive/" -> "a/drive", so that parent_path() is the date folder.
  const fs::path drive_dir = io_internal::DirPathWithName(drive_dir_in);
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  std::error_code ec;
  if (!fs::is_directory(drive_dir, ec)) {
    return NotFoundError("KITTI drive folder " + drive_dir.string() + " not found");
  }
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->drive_dir = drive_dir;

  // --- Scans: files, layout, timestamps.
  const fs::path velo = drive_dir / "velodyne_points";
  SLAM_MMS_ASSIGN_OR_RETURN(const auto files, ListNumberedFiles(velo / "data"));
  if (files.empty()) {
    return NotFoundError("no scan files (NNNNNNNNNN.bin or .txt) in " + (velo / "data").string());
  }
  const std::string ext = files.begin()->second.extension().string();
  if (ext != ".bin" && ext != ".txt") {
    return DataLossError(files.begin()->second.string() +
                         ": unknown scan file extension (expected .bin or .txt)");
  }
  for (const auto& [n, f] : files) {
    if (f.extension().string() != ext) {
      return DataLossError(velo.string() + "/data mixes " + ext + " and " + f.extension().string() +
                           " scan files (" + f.filename().string() + ")");
    }
  }
  impl->layout = ext == ".bin" ? KittiRawLayout::kSync : KittiRawLayout::kExtract;
  const bool extract = impl->layout == KittiRawLayout::kExtract;

  SLAM_MMS_ASSIGN_OR_RETURN(const auto trig, ReadTimestampFile(velo / "timestamps.txt", extract));
  SLAM_MMS_ASSIGN_OR_RETURN(const auto starts,
                            ReadTimestampFile(velo / "timestamps_start.txt", extract));
  SLAM_MMS_ASSIGN_OR_RETURN(const auto ends,
                            ReadTimestampFile(velo / "timestamps_end.txt", extract));
  if (starts.size() != trig.size() || ends.size() != trig.size()) {
    return DataLossError(velo.string() + ": timestamps.txt has " + std::to_string(trig.size()) +
                         " lines, timestamps_start.txt " + std::to_string(starts.size()) +
                         ", timestamps_end.txt " + std::to_string(ends.size()) +
                         "; they must be equal");
  }
  const auto num_lines = static_cast<int64_t>(trig.size());
  if (!extract && static_cast<int64_t>(files.size()) != num_lines) {
    return DataLossError(velo.string() + ": " + std::to_string(files.size()) +
                         " scan files but timestamps.txt has " + std::to_string(num_lines) +
                         " lines");
  }
  if (files.rbegin()->first >= num_lines) {
    return DataLossError(files.rbegin()->second.string() + ": no line for it in " +
                         (velo / "timestamps.txt").string() + " (" + std::to_string(num_lines) +
                         " lines)");
  }
  const int64_t first = options.first_frame;
  const int64_t last = options.last_frame < 0 ? num_lines - 1 : options.last_frame;
  if (first >= num_lines || last >= num_lines) {
    return OutOfRangeError("frame range [" + std::to_string(first) + ", " +
                           std::to_string(options.last_frame) + "] outside drive " +
                           drive_dir.string() + " with frames [0, " +
                           std::to_string(num_lines - 1) + "]");
  }
  size_t lost = 0;
  for (int64_t n = first; n <= last; ++n) {
    const auto i = static_cast<size_t>(n);
    const auto it = files.find(n);
    if (!trig[i] || !starts[i] || !ends[i] || it == files.end()) {
      if (!extract) {
        return NotFoundError((velo / "data").string() + ": scan file " + std::to_string(n) +
                             " missing");
      }
      ++lost;
      continue;
    }
    if (*ends[i] <= *starts[i]) {
      return DataLossError((velo / "timestamps_end.txt").string() + ":" + std::to_string(n + 1) +
                           ": scan end " + ends[i]->ToKittiString() + " not after its start " +
                           starts[i]->ToKittiString() + " (timestamps_start.txt line " +
                           std::to_string(n + 1) + ")");
    }
    if (*trig[i] < *starts[i] || *trig[i] > *ends[i]) {
      SLAM_MMS_LOG(kWarning) << (velo / "timestamps.txt").string() << ":" << n + 1
                             << ": trigger time outside the scan's [start, end]";
    }
    impl->frames.push_back(Impl::Frame{n, it->second, *starts[i], *ends[i], *trig[i]});
  }
  if (lost > 0) {
    SLAM_MMS_LOG(kWarning) << velo.string() << ": " << lost
                           << " lost scans (empty timestamp line or missing file) skipped";
  }
  if (impl->frames.empty()) {
    return DataLossError(velo.string() + ": no readable scan in frame range [" +
                         std::to_string(first) + ", " + std::to_string(last) + "]");
  }

  // --- OXTS.
  const Timestamp t_min = impl->frames.front().start.PlusSeconds(-options.imu_time_margin_s);
  const Timestamp t_max = impl->frames.back().end.PlusSeconds(options.imu_time_margin_s);
  const fs::path oxts_dir = drive_dir / "oxts";
  if (fs::is_directory(oxts_dir, ec)) {
    OxtsSelection sel;
    sel.by_index = !extract;
    sel.first = first;
    sel.last = last;
    sel.t_min = t_min;
    sel.t_max = t_max;
    size_t oxts_lines = 0;
    SLAM_MMS_ASSIGN_OR_RETURN(impl->oxts, ReadOxtsFolder(oxts_dir, extract, sel, &oxts_lines));
    if (!extract && static_cast<int64_t>(oxts_lines) != num_lines) {
      return DataLossError(oxts_dir.string() + "/timestamps.txt has " + std::to_string(oxts_lines) +
                           " lines but the drive has " + std::to_string(num_lines) +
                           " scans (sync layout: one OXTS record per scan)");
    }
  } else {
    SLAM_MMS_LOG(kWarning) << drive_dir.string() << ": no oxts/ folder; no GNSS/INS records";
  }
  const fs::path imu_dir = drive_dir / "oxts_100hz";
  if (fs::is_directory(imu_dir, ec)) {
    OxtsSelection sel;
    sel.by_index = false;
    sel.t_min = t_min;
    sel.t_max = t_max;
    size_t lines = 0;
    SLAM_MMS_ASSIGN_OR_RETURN(impl->imu_oxts, ReadOxtsFolder(imu_dir, true, sel, &lines));
    impl->has_imu_100hz = true;
  } else {
    impl->imu_oxts = impl->oxts;
  }
  if (options.oxts_inertial_delay_s) {
    impl->oxts_inertial_delay_s = *options.oxts_inertial_delay_s;
  } else if (impl->imu_oxts.size() >= 3) {
    SLAM_MMS_ASSIGN_OR_RETURN(impl->oxts_inertial_delay_estimate,
                              EstimateOxtsInertialDelay(impl->imu_oxts));
    const OxtsInertialDelay& e = *impl->oxts_inertial_delay_estimate;
    if (e.clear) impl->oxts_inertial_delay_s = e.delay_s;
    SLAM_MMS_LOG(kInfo) << drive_dir.string() << ": OXTS rates fit the attitudes best "
                        << e.delay_s * 1e3 << " ms later (RMS " << e.rms_at_delay_radps
                        << " against " << e.rms_at_zero_radps << " rad/s, " << e.samples
                        << " records): IMU samples stamped " << impl->oxts_inertial_delay_s * 1e3
                        << " ms early" << (e.clear ? "" : " (not clear: as recorded)");
  }

  // --- Calibration.
  std::vector<fs::path> candidates;
  if (!options.calib_dir.empty()) {
    candidates.push_back(fs::path(options.calib_dir) / "calib_imu_to_velo.txt");
  } else {
    candidates.push_back(drive_dir / "calib_imu_to_velo.txt");
    candidates.push_back(drive_dir.parent_path() / "calib_imu_to_velo.txt");
  }
  for (const auto& c : candidates) {
    if (fs::exists(c, ec)) {
      impl->calibration_file = c;
      break;
    }
  }
  if (impl->calibration_file.empty()) {
    std::string tried;
    for (const auto& c : candidates) tried += (tried.empty() ? "" : ", ") + c.string();
    if (!options.allow_missing_calibration) {
      return NotFoundError("calibration file calib_imu_to_velo.txt not found (tried " + tried +
                           ")");
    }
    SLAM_MMS_LOG(kWarning) << "calib_imu_to_velo.txt not found (tried " << tried
                           << "); using identity T_lidar_body";
  } else {
    SLAM_MMS_ASSIGN_OR_RETURN(impl->T_lidar_body,
                              ReadKittiRigidCalibration(impl->calibration_file));
  }
  return KittiRawReader(std::move(impl));
}

const KittiRawReader::Options& KittiRawReader::options() const { return impl_->options; }
KittiRawLayout KittiRawReader::layout() const { return impl_->layout; }
const fs::path& KittiRawReader::drive_dir() const { return impl_->drive_dir; }
size_t KittiRawReader::NumScans() const { return impl_->frames.size(); }
int64_t KittiRawReader::FrameIndex(size_t i) const { return impl_->frames.at(i).index; }
Timestamp KittiRawReader::ScanStart(size_t i) const { return impl_->frames.at(i).start; }
Timestamp KittiRawReader::ScanEnd(size_t i) const { return impl_->frames.at(i).end; }
Timestamp KittiRawReader::ScanTrigger(size_t i) const { return impl_->frames.at(i).trigger; }
const std::vector<StampedOxts>& KittiRawReader::OxtsRecords() const { return impl_->oxts; }
const std::vector<StampedOxts>& KittiRawReader::ImuOxtsRecords() const { return impl_->imu_oxts; }
bool KittiRawReader::HasImu100Hz() const { return impl_->has_imu_100hz; }
const Eigen::Isometry3d& KittiRawReader::T_lidar_body() const { return impl_->T_lidar_body; }
const fs::path& KittiRawReader::calibration_file() const { return impl_->calibration_file; }
uint64_t KittiRawReader::TotalDroppedPoints() const { return impl_->dropped.load(); }

std::vector<GnssFix> KittiRawReader::GnssFixes() const {
  std::vector<GnssFix> fixes;
  fixes.reserve(impl_->oxts.size());
  for (const auto& r : impl_->oxts) fixes.push_back(ToGnssFix(r.record, r.stamp));
  return fixes;
}

std::vector<ImuSample> KittiRawReader::ImuSamples() const {
  std::vector<ImuSample> samples;
  samples.reserve(impl_->imu_oxts.size());
  const double delay = impl_->oxts_inertial_delay_s;
  for (const auto& r : impl_->imu_oxts) {
    samples.push_back(ToImuSample(r.record, delay == 0.0 ? r.stamp : r.stamp.PlusSeconds(-delay)));
  }
  return samples;
}

double KittiRawReader::oxts_inertial_delay_s() const { return impl_->oxts_inertial_delay_s; }

const std::optional<OxtsInertialDelay>& KittiRawReader::oxts_inertial_delay_estimate() const {
  return impl_->oxts_inertial_delay_estimate;
}

double KittiAzimuthFraction(double x, double y, SpinDirection spin) {
  const double a = std::atan2(y, x) / M_PI;  // (-1, 1]
  return spin == SpinDirection::kClockwise ? 0.5 * (-a + 1.0) : 0.5 * (a + 1.0);
}

StatusOr<Scan> KittiRawReader::ReadScan(size_t i) const {
  if (i >= impl_->frames.size()) {
    return OutOfRangeError("KittiRawReader::ReadScan(" + std::to_string(i) + "): only " +
                           std::to_string(impl_->frames.size()) + " scans");
  }
  const Impl::Frame& frame = impl_->frames[i];
  std::vector<float> xyzr;
  SLAM_MMS_RETURN_IF_ERROR(io_internal::ReadKittiRawScan(frame.file, &xyzr));
  const size_t n = xyzr.size() / 4;
  if (n == 0) return DataLossError(frame.file.string() + ": scan contains no points");

  Scan scan;
  scan.index = frame.index;
  scan.stamp_start = frame.start;
  scan.stamp_end = frame.end;
  scan.stamp_trigger = frame.trigger;
  scan.source = frame.file.string();

  const size_t dropped = io_internal::KittiPointsToCloud(
      xyzr, impl_->options, frame.end.SecondsSince(frame.start), &scan.cloud);
  if (dropped > 0) {
    impl_->dropped += dropped;
    SLAM_MMS_LOG(kWarning) << frame.file.string() << ": dropped " << dropped << " of " << n
                           << " points with NaN/Inf values";
  }
  if (scan.cloud.empty()) {
    return DataLossError(frame.file.string() + ": scan has no finite point (" + std::to_string(n) +
                         " points, all NaN/Inf)");
  }
  return scan;
}

}  // namespace slam_mms
