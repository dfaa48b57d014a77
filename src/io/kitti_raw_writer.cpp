#include "slam_mms/io/kitti_raw_writer.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "io/file_util.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

namespace fs = std::filesystem;

namespace {

std::string NumberedName(size_t n, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%010zu%s", n, ext);
  return buf;
}

// One OXTS folder: data/%010d.txt + timestamps.txt.
struct OxtsFolder {
  fs::path dir;
  std::ofstream stamps;
  size_t count = 0;
  Timestamp last;

  Status Open(const fs::path& d) {
    dir = d;
    std::error_code ec;
    fs::create_directories(dir / "data", ec);
    if (ec)
      return UnavailableError("cannot create " + (dir / "data").string() + ": " + ec.message());
    stamps.open(dir / "timestamps.txt", std::ios::binary | std::ios::trunc);
    if (!stamps) return UnavailableError("cannot create " + (dir / "timestamps.txt").string());
    return io_internal::WriteFileBytes(dir / "dataformat.txt", OxtsDataFormatText());
  }

  Status Add(Timestamp stamp, const OxtsRecord& record, const char* what) {
    if (count > 0 && stamp <= last) {
      return InvalidArgumentError(std::string(what) + ": stamp " + stamp.ToKittiString() +
                                  " not after the previous record's " + last.ToKittiString() +
                                  " (record " + std::to_string(count) + ")");
    }
    for (const double v : record.ToArray()) {
      if (!std::isfinite(v)) {
        return InvalidArgumentError(std::string(what) + ": record " + std::to_string(count) +
                                    " has a non-finite field");
      }
    }
    SLAM_MMS_RETURN_IF_ERROR(io_internal::WriteFileBytes(dir / "data" / NumberedName(count, ".txt"),
                                                         FormatOxtsLine(record) + "\n"));
    stamps << stamp.ToKittiString() << '\n';
    if (!stamps) return DataLossError("cannot write " + (dir / "timestamps.txt").string());
    last = stamp;
    ++count;
    return OkStatus();
  }
};

}  // namespace

struct KittiRawWriter::Impl {
  Options options;
  fs::path drive_dir;
  fs::path velo_dir;
  std::ofstream ts, ts_start, ts_end;
  size_t num_scans = 0;
  Timestamp last_start;
  OxtsFolder oxts;
  OxtsFolder imu;
  bool oxts_opened = false;  // oxts/ is created at the first AddOxts
  bool imu_opened = false;
  bool finished = false;
  std::vector<char> buffer;
};

KittiRawWriter::KittiRawWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
KittiRawWriter::KittiRawWriter(KittiRawWriter&&) noexcept = default;
KittiRawWriter& KittiRawWriter::operator=(KittiRawWriter&&) noexcept = default;

KittiRawWriter::~KittiRawWriter() {
  if (impl_ && !impl_->finished) {
    const Status s = Finish();
    if (!s.ok()) {
      SLAM_MMS_LOG(kError) << "KittiRawWriter: " << s.ToString();
    }
  }
}

StatusOr<KittiRawWriter> KittiRawWriter::Create(const fs::path& drive_dir) {
  return Create(drive_dir, Options());
}

StatusOr<KittiRawWriter> KittiRawWriter::Create(const fs::path& drive_dir_in,
                                                const Options& options) {
  // "a/drive/" -> "a/drive", so that parent_path() is the date folder.
  const fs::path drive_dir = io_internal::DirPathWithName(drive_dir_in);
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (drive_dir.empty()) return InvalidArgumentError("KittiRawWriter: empty drive folder path");
  std::error_code ec;
  if (fs::exists(drive_dir, ec) && !fs::is_empty(drive_dir, ec)) {
    if (!options.overwrite) {
      return InvalidArgumentError("KittiRawWriter: " + drive_dir.string() +
                                  " exists and is not empty (set Options::overwrite)");
    }
    fs::remove_all(drive_dir, ec);
    if (ec) return UnavailableError("cannot remove " + drive_dir.string() + ": " + ec.message());
  }
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->drive_dir = drive_dir;
  impl->velo_dir = drive_dir / "velodyne_points";
  fs::create_directories(impl->velo_dir / "data", ec);
  if (ec) {
    return UnavailableError("cannot create " + (impl->velo_dir / "data").string() + ": " +
                            ec.message());
  }
  impl->ts.open(impl->velo_dir / "timestamps.txt", std::ios::binary | std::ios::trunc);
  impl->ts_start.open(impl->velo_dir / "timestamps_start.txt", std::ios::binary | std::ios::trunc);
  impl->ts_end.open(impl->velo_dir / "timestamps_end.txt", std::ios::binary | std::ios::trunc);
  if (!impl->ts || !impl->ts_start || !impl->ts_end) {
    return UnavailableError("cannot create the timestamp files in " + impl->velo_dir.string());
  }
  return KittiRawWriter(std::move(impl));
}

Status KittiRawWriter::WriteCalibration(const Eigen::Isometry3d& T_lidar_body) {
  const Eigen::Matrix3d R = T_lidar_body.linear();
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!T_lidar_body.matrix().allFinite() || err > 1e-6 || R.determinant() < 0.0) {
    return InvalidArgumentError("KittiRawWriter::WriteCalibration: T_lidar_body is not rigid");
  }
  fs::path parent = impl_->drive_dir.parent_path();
  if (parent.empty()) parent = ".";
  char buf[64];
  std::string imu = "calib_time: slam_mms\nR:";
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      std::snprintf(buf, sizeof(buf), " %.9e", R(r, c));
      imu += buf;
    }
  }
  imu += "\nT:";
  for (int k = 0; k < 3; ++k) {
    std::snprintf(buf, sizeof(buf), " %.9e", T_lidar_body.translation()(k));
    imu += buf;
  }
  imu += "\n";
  SLAM_MMS_RETURN_IF_ERROR(io_internal::WriteFileBytes(parent / "calib_imu_to_velo.txt", imu));
  // Placeholders: KITTI's velo->cam axes permutation (camera x right, y down, z forward) without
  // offset, and a KITTI-like pinhole camera 0.
  SLAM_MMS_RETURN_IF_ERROR(io_internal::WriteFileBytes(
      parent / "calib_velo_to_cam.txt",
      "calib_time: slam_mms placeholder\n"
      "R: 0.000000e+00 -1.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 -1.000000e+00 "
      "1.000000e+00 0.000000e+00 0.000000e+00\n"
      "T: 0.000000e+00 0.000000e+00 0.000000e+00\n"
      "delta_f: 0.000000e+00 0.000000e+00\n"
      "delta_c: 0.000000e+00 0.000000e+00\n"));
  return io_internal::WriteFileBytes(
      parent / "calib_cam_to_cam.txt",
      "calib_time: slam_mms placeholder\n"
      "corner_dist: 0.000000e+00\n"
      "S_00: 1.392000e+03 5.120000e+02\n"
      "K_00: 7.215377e+02 0.000000e+00 6.960000e+02 0.000000e+00 7.215377e+02 2.560000e+02 "
      "0.000000e+00 0.000000e+00 1.000000e+00\n"
      "D_00: 0.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00\n"
      "R_00: 1.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00 "
      "0.000000e+00 0.000000e+00 1.000000e+00\n"
      "T_00: 0.000000e+00 0.000000e+00 0.000000e+00\n"
      "S_rect_00: 1.242000e+03 3.750000e+02\n"
      "R_rect_00: 1.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00 "
      "0.000000e+00 0.000000e+00 1.000000e+00\n"
      "P_rect_00: 7.215377e+02 0.000000e+00 6.960000e+02 0.000000e+00 0.000000e+00 7.215377e+02 "
      "2.560000e+02 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00\n");
}

Status KittiRawWriter::AddScan(const Scan& scan) {
  Impl& s = *impl_;
  if (s.finished) return FailedPreconditionError("KittiRawWriter::AddScan after Finish()");
  const std::string what = "KittiRawWriter::AddScan (scan " + std::to_string(s.num_scans) + ")";
  if (scan.stamp_end <= scan.stamp_start) {
    return InvalidArgumentError(what + ": stamp_end " + scan.stamp_end.ToKittiString() +
                                " not after stamp_start " + scan.stamp_start.ToKittiString());
  }
  if (s.num_scans > 0 && scan.stamp_start <= s.last_start) {
    return InvalidArgumentError(what + ": stamp_start " + scan.stamp_start.ToKittiString() +
                                " not after the previous scan's " + s.last_start.ToKittiString());
  }
  Timestamp trigger = scan.stamp_trigger;
  if (trigger == Timestamp() && s.options.trigger_defaults_to_midpoint) {
    trigger = Timestamp::FromNanoseconds(
        scan.stamp_start.nanoseconds() +
        (scan.stamp_end.nanoseconds() - scan.stamp_start.nanoseconds()) / 2);
  }
  if (trigger < scan.stamp_start || trigger > scan.stamp_end) {
    return InvalidArgumentError(what + ": stamp_trigger " + trigger.ToKittiString() +
                                " outside [stamp_start, stamp_end]");
  }
  const PointCloud& c = scan.cloud;
  if (c.empty()) return InvalidArgumentError(what + ": no points");
  if (c.intensities().size() != c.size()) {
    return InvalidArgumentError(what + ": " + std::to_string(c.intensities().size()) +
                                " intensities for " + std::to_string(c.size()) + " points");
  }
  s.buffer.resize(16 * c.size());
  for (size_t k = 0; k < c.size(); ++k) {
    const float v[4] = {c.points()[k].x(), c.points()[k].y(), c.points()[k].z(),
                        c.intensities()[k]};
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]) ||
        !std::isfinite(v[3])) {
      return InvalidArgumentError(what + ": point " + std::to_string(k) + " is not finite");
    }
    std::memcpy(s.buffer.data() + 16 * k, v, 16);
  }
  const fs::path file = s.velo_dir / "data" / NumberedName(s.num_scans, ".bin");
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    if (!out) return UnavailableError("cannot create " + file.string());
    out.write(s.buffer.data(), static_cast<std::streamsize>(s.buffer.size()));
    out.close();
    if (!out) return DataLossError("cannot write " + file.string());
  }
  s.ts << trigger.ToKittiString() << '\n';
  s.ts_start << scan.stamp_start.ToKittiString() << '\n';
  s.ts_end << scan.stamp_end.ToKittiString() << '\n';
  if (!s.ts || !s.ts_start || !s.ts_end) {
    return DataLossError("cannot write the timestamp files in " + s.velo_dir.string());
  }
  s.last_start = scan.stamp_start;
  ++s.num_scans;
  return OkStatus();
}

Status KittiRawWriter::AddOxts(Timestamp stamp, const OxtsRecord& record) {
  if (impl_->finished) return FailedPreconditionError("KittiRawWriter::AddOxts after Finish()");
  if (!impl_->oxts_opened) {
    SLAM_MMS_RETURN_IF_ERROR(impl_->oxts.Open(impl_->drive_dir / "oxts"));
    impl_->oxts_opened = true;
  }
  return impl_->oxts.Add(stamp, record, "KittiRawWriter::AddOxts");
}

Status KittiRawWriter::AddImuOxts(Timestamp stamp, const OxtsRecord& record) {
  if (impl_->finished) return FailedPreconditionError("KittiRawWriter::AddImuOxts after Finish()");
  if (!impl_->imu_opened) {
    SLAM_MMS_RETURN_IF_ERROR(impl_->imu.Open(impl_->drive_dir / "oxts_100hz"));
    impl_->imu_opened = true;
  }
  return impl_->imu.Add(stamp, record, "KittiRawWriter::AddImuOxts");
}

Status KittiRawWriter::Finish() {
  Impl& s = *impl_;
  if (s.finished) return OkStatus();
  s.finished = true;
  s.ts.close();
  s.ts_start.close();
  s.ts_end.close();
  if (s.oxts_opened) s.oxts.stamps.close();
  if (s.imu_opened) s.imu.stamps.close();
  if (!s.ts || !s.ts_start || !s.ts_end || (s.oxts_opened && !s.oxts.stamps) ||
      (s.imu_opened && !s.imu.stamps)) {
    return DataLossError("KittiRawWriter::Finish: closing the timestamp files of " +
                         s.drive_dir.string() + " failed");
  }
  if (s.oxts.count > 0 && s.oxts.count != s.num_scans) {
    return FailedPreconditionError("KittiRawWriter::Finish: " + std::to_string(s.oxts.count) +
                                   " OXTS records for " + std::to_string(s.num_scans) +
                                   " scans (the sync layout needs one per scan)");
  }
  return OkStatus();
}

size_t KittiRawWriter::NumScans() const { return impl_->num_scans; }
size_t KittiRawWriter::NumOxts() const { return impl_->oxts.count; }
size_t KittiRawWriter::NumImuOxts() const { return impl_->imu.count; }
const fs::path& KittiRawWriter::drive_dir() const { return impl_->drive_dir; }

}  // namespace slam_mms
