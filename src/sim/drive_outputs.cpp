#include "sim/drive_outputs.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "slam_mms/io/trajectory_io.hpp"

namespace slam_mms::sim {

void GroundTruthLog::Add(Timestamp stamp, const BodyState& state, const ImuSample& truth,
                         const ImuSimulator& imu, const GnssSample& gnss) {
  (void)poses.Add(stamp, state.T_world_body);
  rows.push_back(
      {stamp, truth.accel_mps2, truth.gyro_radps, imu.accel_bias(), imu.gyro_bias(), gnss});
}

Status GroundTruthLog::WriteCsv(const std::filesystem::path& dir) const {
  {
    std::ofstream f(dir / "imu_truth.csv");
    if (!f) return InternalError("cannot write " + (dir / "imu_truth.csv").string());
    f << "stamp_ns,fx,fy,fz,wx,wy,wz,accel_bias_x,accel_bias_y,accel_bias_z,gyro_bias_x,gyro_bias_"
         "y,gyro_bias_z\n";
    f << std::setprecision(17);
    for (const Row& r : rows) {
      f << r.stamp.nanoseconds();
      for (const Eigen::Vector3d* v : {&r.f_true, &r.w_true, &r.accel_bias, &r.gyro_bias})
        f << ',' << v->x() << ',' << v->y() << ',' << v->z();
      f << '\n';
    }
    if (!f) return InternalError("write failed: " + (dir / "imu_truth.csv").string());
  }
  std::ofstream f(dir / "gnss.csv");
  if (!f) return InternalError("cannot write " + (dir / "gnss.csv").string());
  f << "stamp_ns,state,error_e,error_n,error_u,sigma_h,sigma_v,numsats,sky_blockage,scripted_"
       "outage\n";
  f << std::setprecision(10);
  for (const Row& r : rows) {
    f << r.stamp.nanoseconds() << ',' << GnssStateName(r.gnss.state) << ','
      << r.gnss.error_enu_m.x() << ',' << r.gnss.error_enu_m.y() << ',' << r.gnss.error_enu_m.z()
      << ',' << r.gnss.sigma_horizontal_m << ',' << r.gnss.sigma_vertical_m << ','
      << r.gnss.num_satellites << ',' << r.gnss.sky_blockage << ','
      << (r.gnss.in_scripted_outage ? 1 : 0) << '\n';
  }
  if (!f) return InternalError("write failed: " + (dir / "gnss.csv").string());
  return OkStatus();
}

void SceneCloudAccumulator::Add(const std::vector<Eigen::Vector3f>& p,
                                const std::vector<float>& inten) {
  for (size_t i = 0; i < p.size(); ++i) {
    const int64_t x = static_cast<int64_t>(std::floor(p[i].x() * inv_voxel_)) + (1 << 20);
    const int64_t y = static_cast<int64_t>(std::floor(p[i].y() * inv_voxel_)) + (1 << 20);
    const int64_t z = static_cast<int64_t>(std::floor(p[i].z() * inv_voxel_)) + (1 << 20);
    const uint64_t key = (static_cast<uint64_t>(x & 0x1FFFFF) << 42) |
                         (static_cast<uint64_t>(y & 0x1FFFFF) << 21) |
                         static_cast<uint64_t>(z & 0x1FFFFF);
    // Consecutive returns of a ring often share a voxel: skipping repeats of the previous key keeps
    // the result (the first point of each voxel) and saves most hash lookups.
    if (i > 0 && key == last_key_) continue;
    last_key_ = key;
    if (index_.empty()) index_.reserve(1 << 20);
    auto [it, inserted] = index_.emplace(key, static_cast<uint32_t>(map_.cloud.size()));
    if (inserted) map_.cloud.Add(p[i], i < inten.size() ? inten[i] : 0.f);
  }
}

MapCloud SceneCloudAccumulator::Take() {
  index_.clear();
  return std::move(map_);
}

namespace {
std::string Num(double v) {
  char b[40];
  std::snprintf(b, sizeof(b), "%.17g", v);
  return b;
}
std::string Str(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}
}  // namespace

Status WriteScenarioJson(const DriveSimulator::Options& o, const DriveSimulator& sim,
                         const DriveSimulator::Summary& s, const std::filesystem::path& file) {
  std::ofstream f(file);
  if (!f) return InternalError("cannot write " + file.string());
  const auto& tr = sim.trajectory();
  const auto& w = o.world;
  const auto& l = o.lidar;
  const auto& imu = o.imu;
  const auto& g = o.gnss;
  const Eigen::Matrix4d T = o.T_lidar_body.matrix();
  f << "{\n";
  f << "  \"generator\": \"slam_mms_sim\",\n";
  f << "  \"scenario\": " << Str(o.oxts_drive_dir.empty() ? o.scenario : "oxts") << ",\n";
  f << "  \"oxts_drive_dir\": " << Str(o.oxts_drive_dir.string()) << ",\n";
  f << "  \"seed\": " << o.seed << ",\n";
  f << "  \"duration_s\": " << Num(o.duration_s) << ",\n";
  f << "  \"lead_in_s\": " << Num(o.lead_in_s) << ",\n";
  f << "  \"drive\": " << Str(s.drive_name) << ",\n";
  f << "  \"date\": " << Str(o.date) << ",\n  \"drive_id\": " << o.drive_id << ",\n";
  f << "  \"world_frame\": \"local ENU (x east, y north, z up) about origin_wgs84 via "
       "GeographicLib LocalCartesian\",\n";
  f << "  \"origin_wgs84\": {\"latitude_deg\": " << Num(o.origin_latitude_deg)
    << ", \"longitude_deg\": " << Num(o.origin_longitude_deg)
    << ", \"height_m\": " << Num(o.origin_height_m) << "},\n";
  f << "  \"body_frame\": \"IMU/OXTS: x forward, y left, z up\",\n";
  f << "  \"T_lidar_body\": [";
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) f << Num(T(r, c)) << (r == 3 && c == 3 ? "" : ", ");
  f << "],\n";
  f << "  \"gravity_mps2\": " << Num(o.gravity_mps2) << ",\n";
  f << "  \"trajectory\": {\"epoch_ns\": " << tr.epoch().nanoseconds()
    << ", \"start_s\": " << Num(tr.start_s()) << ", \"end_s\": " << Num(tr.end_s())
    << ", \"first_scan_s\": " << Num(sim.first_scan_s())
    << ", \"first_scan_stamp_ns\": " << tr.ToTimestamp(sim.first_scan_s()).nanoseconds()
    << ", \"knot_spacing_s\": " << Num(o.fit.knot_spacing_s)
    << ", \"position_sigma_m\": " << Num(o.fit.position_sigma_m)
    << ", \"angle_sigma_rad\": " << Num(o.fit.angle_sigma_rad)
    << ", \"accel_density\": " << Num(o.fit.accel_density)
    << ", \"angular_accel_density\": " << Num(o.fit.angular_accel_density) << "},\n";
  f << "  \"world\": {\"seed\": " << w.seed << ", \"corridor_m\": " << Num(w.corridor_m)
    << ", \"ground_cell_m\": " << Num(w.ground_cell_m)
    << ", \"body_height_above_road_m\": " << Num(w.body_height_above_road_m)
    << ", \"road_half_width_m\": [" << Num(w.road_half_width_min_m) << ", "
    << Num(w.road_half_width_max_m) << "], \"sidewalk_width_m\": [" << Num(w.sidewalk_width_min_m)
    << ", " << Num(w.sidewalk_width_max_m) << "], \"curb_height_m\": " << Num(w.curb_height_m)
    << ", \"building_height_m\": [" << Num(w.building_height_min_m) << ", "
    << Num(w.building_height_max_m)
    << "], \"building_probability\": " << Num(w.building_probability)
    << ", \"pole_spacing_m\": " << Num(w.pole_spacing_m)
    << ", \"tree_probability\": " << Num(w.tree_probability)
    << ", \"parked_car_probability\": " << Num(w.parked_car_probability);
  const auto& st = sim.world().stats();
  f << ", \"stats\": {\"triangles\": " << st.num_triangles
    << ", \"ground_triangles\": " << st.num_ground_triangles
    << ", \"buildings\": " << st.num_buildings << ", \"trees\": " << st.num_trees
    << ", \"poles\": " << st.num_poles << ", \"cars\": " << st.num_cars
    << ", \"fences\": " << st.num_fences << ", \"path_length_m\": " << Num(st.path_length_m)
    << "}},\n";
  f << "  \"lidar\": {\"model\": \"HDL-64E\", \"elevations_deg\": [";
  Hdl64Lidar lidar(l);
  for (size_t i = 0; i < lidar.elevations_deg().size(); ++i)
    f << (i ? ", " : "") << Num(lidar.elevations_deg()[i]);
  f << "], \"firings_per_revolution\": " << l.firings_per_revolution
    << ", \"rotation_rate_hz\": " << Num(l.rotation_rate_hz)
    << ", \"direction\": \"clockwise from above, start/end at the rear\""
    << ", \"range_noise_sigma_m\": " << Num(l.range_noise_sigma_m)
    << ", \"min_range_m\": " << Num(l.min_range_m) << ", \"max_range_m\": " << Num(l.max_range_m)
    << ", \"min_cos_incidence\": " << Num(l.min_cos_incidence)
    << ", \"reflectance_noise_sigma\": " << Num(l.reflectance_noise_sigma)
    << ", \"elevation_bias_deg\": " << Num(l.elevation_bias_deg)
    << ", \"dropout_base\": " << Num(l.dropout_base) << ", \"dropout_far\": " << Num(l.dropout_far)
    << ", \"motion_compensated\": false},\n";
  f << "  \"imu\": {\"rate_hz\": " << Num(imu.rate_hz)
    << ", \"gyro_noise_density\": " << Num(imu.gyro_noise_density)
    << ", \"gyro_bias_instability\": " << Num(imu.gyro_bias_instability)
    << ", \"gyro_bias_tau_s\": " << Num(imu.gyro_bias_tau_s)
    << ", \"gyro_turn_on_bias_sigma\": " << Num(imu.gyro_turn_on_bias_sigma)
    << ", \"accel_noise_density\": " << Num(imu.accel_noise_density)
    << ", \"accel_bias_instability\": " << Num(imu.accel_bias_instability)
    << ", \"accel_bias_tau_s\": " << Num(imu.accel_bias_tau_s)
    << ", \"accel_turn_on_bias_sigma\": " << Num(imu.accel_turn_on_bias_sigma) << "},\n";
  f << "  \"gnss\": {\"best_state\": " << Str(GnssStateName(g.best_state))
    << ", \"sigma_fixed_m\": [" << Num(g.sigma_fixed_h_m) << ", " << Num(g.sigma_fixed_v_m)
    << "], \"sigma_float_m\": [" << Num(g.sigma_float_h_m) << ", " << Num(g.sigma_float_v_m)
    << "], \"sigma_sps_m\": [" << Num(g.sigma_sps_h_m) << ", " << Num(g.sigma_sps_v_m)
    << "], \"multipath_rate_hz\": " << Num(g.multipath_rate_hz)
    << ", \"multipath_sigma_m\": " << Num(g.multipath_sigma_m)
    << ", \"urban_canyon_scale\": " << Num(g.urban_canyon_scale) << ", \"blockage_thresholds\": ["
    << Num(g.blockage_float) << ", " << Num(g.blockage_sps) << ", " << Num(g.blockage_none)
    << "], \"outages_relative_to_first_scan\": [";
  for (size_t i = 0; i < g.outages.size(); ++i)
    f << (i ? ", " : "") << "{\"start_s\": " << Num(g.outages[i].start_s)
      << ", \"duration_s\": " << Num(g.outages[i].duration_s) << "}";
  f << "], \"antenna_above_imu_m\": 0.75},\n";
  f << "  \"ins\": {\"roll_pitch_sigma_rad\": " << Num(o.ins_roll_pitch_sigma_rad)
    << ", \"yaw_sigma_rad\": " << Num(o.ins_yaw_sigma_rad)
    << ", \"velocity_sigma_mps\": " << Num(o.ins_velocity_sigma_mps) << "},\n";
  f << "  \"scene_cloud_voxel_m\": " << Num(o.scene_cloud_voxel_m) << ",\n";
  f << "  \"summary\": {\"scans\": " << s.num_scans << ", \"points\": " << s.num_points
    << ", \"imu_records\": " << s.num_imu_records << ", \"scene_points\": " << s.num_scene_points
    << ", \"simulated_seconds\": " << Num(s.simulated_seconds)
    << ", \"path_length_m\": " << Num(s.path_length_m)
    << ", \"gnss_fraction\": {\"rtk_fixed\": " << Num(s.fraction_fixed)
    << ", \"rtk_float\": " << Num(s.fraction_float) << ", \"sps\": " << Num(s.fraction_sps)
    << ", \"none\": " << Num(s.fraction_none) << "}}\n";
  f << "}\n";
  if (!f) return InternalError("write failed: " + file.string());
  return OkStatus();
}

}  // namespace slam_mms::sim
