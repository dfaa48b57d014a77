// Pose samples of a real KITTI OXTS drive folder, in local ENU through GeographicLib.
#include <GeographicLib/LocalCartesian.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "slam_mms/io/kitti_timestamp.hpp"
#include "slam_mms/io/oxts_record.hpp"
#include "slam_mms/sim/reference_trajectory.hpp"

namespace slam_mms::sim {

StatusOr<OxtsPoseSamples> LoadOxtsPoseSamples(const std::filesystem::path& drive_dir,
                                              double origin_latitude_deg,
                                              double origin_longitude_deg, double origin_height_m,
                                              bool origin_from_first) {
  const std::filesystem::path oxts_dir = drive_dir / "oxts";
  const std::filesystem::path stamps_file = oxts_dir / "timestamps.txt";
  std::ifstream stamps_in(stamps_file);
  if (!stamps_in) return NotFoundError("cannot open " + stamps_file.string());
  OxtsPoseSamples out;
  std::string line;
  int index = -1;
  bool have_origin = !origin_from_first;
  GeographicLib::LocalCartesian enu(origin_latitude_deg, origin_longitude_deg, origin_height_m);
  Timestamp last;
  while (std::getline(stamps_in, line)) {
    ++index;
    if (line.find_first_not_of(" \t\r") == std::string::npos) {
      ++out.num_dropped;  // KITTI marks lost records with empty timestamp lines
      continue;
    }
    auto stamp = ParseKittiTimestamp(line);
    if (!stamp.ok()) return stamp.status().WithContext(stamps_file.string());
    char name[32];
    std::snprintf(name, sizeof(name), "%010d.txt", index);
    const std::filesystem::path file = oxts_dir / "data" / name;
    std::ifstream data_in(file);
    std::string data_line;
    if (!data_in || !std::getline(data_in, data_line)) {
      ++out.num_dropped;
      continue;
    }
    auto record = ParseOxtsLine(data_line, file.string(), 1);
    if (!record.ok()) return record.status();
    if (!out.samples.empty() && *stamp <= last.PlusSeconds(1e-3)) {
      ++out.num_dropped;
      continue;
    }
    if (!have_origin) {
      enu.Reset(record->lat_deg, record->lon_deg, record->alt_m);
      have_origin = true;
    }
    if (out.samples.empty()) out.epoch = *stamp;
    last = *stamp;
    PoseSample s;
    s.t_s = stamp->SecondsSince(out.epoch);
    s.record = index;
    double x, y, z;
    enu.Forward(record->lat_deg, record->lon_deg, record->alt_m, x, y, z);
    s.p_world = Eigen::Vector3d(x, y, z);
    s.rpy_rad = Eigen::Vector3d(record->roll_rad, record->pitch_rad, record->yaw_rad);
    // vf, vl: forward and left, parallel to the earth's surface; vu: up. So world = Rz(yaw) v.
    const double cy = std::cos(record->yaw_rad), sy = std::sin(record->yaw_rad);
    s.v_world_mps = Eigen::Vector3d(cy * record->vf - sy * record->vl,
                                    sy * record->vf + cy * record->vl, record->vu);
    s.has_velocity = s.v_world_mps.allFinite();
    if (!s.has_velocity) s.v_world_mps.setZero();
    if (std::isfinite(record->pos_accuracy_m) && record->pos_accuracy_m > 0.0) {
      s.position_sigma_m = record->pos_accuracy_m;
    }
    out.samples.push_back(s);
  }
  if (out.samples.size() < 4) {
    return DataLossError(drive_dir.string() + ": fewer than 4 usable OXTS records");
  }
  out.origin_latitude_deg = enu.LatitudeOrigin();
  out.origin_longitude_deg = enu.LongitudeOrigin();
  out.origin_height_m = enu.HeightOrigin();
  return out;
}

std::vector<ImplausibleMotion> FindImplausibleMotion(const std::vector<PoseSample>& samples,
                                                     double max_sideways_mps,
                                                     double max_vertical_mps) {
  std::vector<ImplausibleMotion> out;
  for (size_t i = 0; i < samples.size(); ++i) {
    const PoseSample& s = samples[i];
    if (!s.has_velocity) continue;
    const double yaw = s.rpy_rad.z();
    const double sideways =
        std::abs(-std::sin(yaw) * s.v_world_mps.x() + std::cos(yaw) * s.v_world_mps.y());
    const double vertical = std::abs(s.v_world_mps.z());
    if (!(sideways > max_sideways_mps || vertical > max_vertical_mps)) continue;
    if (out.empty() || s.t_s - out.back().to_s >= 1.0) {
      ImplausibleMotion span;
      span.from_s = s.t_s;
      span.first_sample = i;
      span.first_record = s.record;
      out.push_back(span);
    }
    ImplausibleMotion& span = out.back();
    span.to_s = s.t_s;
    span.last_sample = i;
    span.last_record = s.record;
    span.max_sideways_mps = std::max(span.max_sideways_mps, sideways);
    span.max_vertical_mps = std::max(span.max_vertical_mps, vertical);
  }
  return out;
}

}  // namespace slam_mms::sim
