#pragma once
// Test-only reader of the real KITTI raw frames in ../shared/data (drive 0013): Velodyne .bin
// scans (float32 x y z r), OXTS records (30 numbers), timestamps and calib_imu_to_velo. Read
// directly so the registration tests depend on nothing but core. OXTS poses follow the KITTI
// devkit (convertOxtsToPose: Mercator with the first record's latitude scale, R = Rz Ry Rx).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/point_cloud.hpp"

namespace slam_mms::testing {

/// Seconds since midnight of "YYYY-MM-DD HH:MM:SS.fffffffff".
inline double ParseKittiTimeOfDay(const std::string& line) {
  const size_t sp = line.find(' ');
  if (sp == std::string::npos) return NAN;
  int h = 0, m = 0;
  double s = 0.0;
  if (std::sscanf(line.c_str() + sp + 1, "%d:%d:%lf", &h, &m, &s) != 3) return NAN;
  return h * 3600.0 + m * 60.0 + s;
}

inline std::vector<double> ReadKittiTimes(const std::filesystem::path& file) {
  std::vector<double> t;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty()) t.push_back(ParseKittiTimeOfDay(line));
  }
  return t;
}

inline std::string FrameName(int i, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%010d.%s", i, ext);
  return buf;
}

/// A Velodyne scan (x y z in the lidar frame; intensities).
inline PointCloud ReadVelodyneBin(const std::filesystem::path& file) {
  PointCloud cloud;
  std::ifstream in2(file, std::ios::binary | std::ios::ate);
  if (!in2) return cloud;
  const std::streamsize bytes = in2.tellg();
  in2.seekg(0);
  std::vector<float> v(static_cast<size_t>(bytes) / sizeof(float));
  in2.read(reinterpret_cast<char*>(v.data()),
           static_cast<std::streamsize>(v.size() * sizeof(float)));
  cloud.reserve(v.size() / 4);
  for (size_t i = 0; i + 3 < v.size(); i += 4) cloud.Add({v[i], v[i + 1], v[i + 2]}, v[i + 3]);
  return cloud;
}

/// T_velo_imu from calib_imu_to_velo.txt (maps IMU-frame points into the Velodyne frame).
inline Eigen::Isometry3d ReadTVeloImu(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::string key;
    ss >> key;
    if (key == "R:") {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) ss >> R(r, c);
    } else if (key == "T:") {
      ss >> t.x() >> t.y() >> t.z();
    }
  }
  return MakeIsometry(R, t);
}

/// All OXTS poses T_world_imu of the drive (KITTI devkit convention, world = Mercator at record 0).
inline std::vector<Eigen::Isometry3d> ReadOxtsPoses(const std::filesystem::path& oxts_dir, int n) {
  std::vector<Eigen::Isometry3d> poses;
  double scale = 0.0;
  constexpr double er = 6378137.0;
  for (int i = 0; i < n; ++i) {
    std::ifstream in(oxts_dir / "data" / FrameName(i, "txt"));
    double v[30] = {};
    for (double& x : v) in >> x;
    if (!in) break;
    const double lat = v[0], lon = v[1], alt = v[2];
    if (i == 0) scale = std::cos(lat * M_PI / 180.0);
    const double tx = scale * lon * M_PI * er / 180.0;
    const double ty = scale * er * std::log(std::tan((90.0 + lat) * M_PI / 360.0));
    poses.push_back(MakeIsometry(FromRollPitchYaw(v[3], v[4], v[5]), Eigen::Vector3d(tx, ty, alt)));
  }
  return poses;
}

/// Pose at time t from stamped poses (InterpolatePose; extrapolates at the ends).
inline Eigen::Isometry3d PoseAt(const std::vector<double>& times,
                                const std::vector<Eigen::Isometry3d>& poses, double t) {
  size_t i = 0;
  while (i + 2 < times.size() && times[i + 1] < t) ++i;
  const double alpha = (t - times[i]) / (times[i + 1] - times[i]);
  return InterpolatePose(poses[i], poses[i + 1], alpha);
}

/// The drive: scans de-skewed to their start time with the OXTS motion (the paper de-skews with
/// the INS; KITTI raw point time t = 0.5 (1 - atan2(y, x) / pi) over [start, end], see
/// ARCHITECTURE.md), and the OXTS lidar poses at scan start.
struct KittiDrive {
  std::filesystem::path dir;
  Eigen::Isometry3d T_velo_imu;
  std::vector<double> scan_start, scan_end, oxts_time;
  std::vector<Eigen::Isometry3d> T_world_imu;

  bool Load(const std::filesystem::path& drive_dir, int n) {
    dir = drive_dir;
    T_velo_imu = ReadTVeloImu(drive_dir.parent_path() / "calib_imu_to_velo.txt");
    scan_start = ReadKittiTimes(drive_dir / "velodyne_points" / "timestamps_start.txt");
    scan_end = ReadKittiTimes(drive_dir / "velodyne_points" / "timestamps_end.txt");
    oxts_time = ReadKittiTimes(drive_dir / "oxts" / "timestamps.txt");
    T_world_imu = ReadOxtsPoses(drive_dir / "oxts", n);
    oxts_time.resize(T_world_imu.size());
    return T_world_imu.size() >= 2 && scan_start.size() >= static_cast<size_t>(n);
  }
  Eigen::Isometry3d TWorldLidar(double t) const {
    return PoseAt(oxts_time, T_world_imu, t) * T_velo_imu.inverse();
  }
  /// OXTS relative lidar motion between the starts of scans a and b: T_lidar_a_lidar_b.
  Eigen::Isometry3d RelativeLidar(int a, int b) const {
    return TWorldLidar(scan_start[static_cast<size_t>(a)]).inverse() *
           TWorldLidar(scan_start[static_cast<size_t>(b)]);
  }
  /// Scan i in the lidar frame at its start time; deskew = false keeps the raw points.
  PointCloud Scan(int i, bool deskew) const {
    PointCloud raw = ReadVelodyneBin(dir / "velodyne_points" / "data" / FrameName(i, "bin"));
    if (!deskew) return raw;
    const double t0 = scan_start[static_cast<size_t>(i)];
    const double t1 = scan_end[static_cast<size_t>(i)];
    const Eigen::Isometry3d T_start_world = TWorldLidar(t0).inverse();
    // Per azimuth bin (0.1 deg) to keep it fast.
    constexpr int kBins = 3600;
    std::vector<Eigen::Isometry3d> T_start_t(kBins);
    for (int b = 0; b < kBins; ++b) {
      const double frac = (b + 0.5) / kBins;
      T_start_t[static_cast<size_t>(b)] = T_start_world * TWorldLidar(t0 + frac * (t1 - t0));
    }
    for (auto& p : raw.points()) {
      const double frac = 0.5 * (1.0 - std::atan2(p.y(), p.x()) / M_PI);
      const int b = std::min(kBins - 1, std::max(0, static_cast<int>(frac * kBins)));
      p = (T_start_t[static_cast<size_t>(b)] * p.cast<double>()).cast<float>();
    }
    return raw;
  }
};

}  // namespace slam_mms::testing
