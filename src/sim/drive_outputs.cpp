#include "sim/drive_outputs.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "sim/random.hpp"
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
    internal::VoxelCell cell;
    if (!grid_.CellOf(p[i], &cell)) continue;
    // Consecutive returns of a ring often share a voxel: skipping repeats of the previous cell
    // keeps the result (the first point of each voxel) and saves most hash lookups.
    if (have_last_ && cell == last_cell_) continue;
    last_cell_ = cell;
    have_last_ = true;
    if (index_.empty()) index_.reserve(1 << 20);
    auto [it, inserted] = index_.emplace(cell, static_cast<uint32_t>(map_.cloud.size()));
    if (inserted) map_.cloud.Add(p[i], i < inten.size() ? inten[i] : 0.f);
  }
}

MapCloud SceneCloudAccumulator::Take() {
  index_.clear();
  have_last_ = false;
  return std::move(map_);
}

Status WriteScenarioJson(const DriveSimulator::Options& o, const DriveSimulator& sim,
                         const DriveSimulator::Summary& s, const std::filesystem::path& file) {
  using Json = nlohmann::ordered_json;
  const auto& tr = sim.trajectory();
  const auto& w = o.world;
  const auto& l = o.lidar;
  const auto& imu = o.imu;
  const auto& g = o.gnss;
  const Eigen::Matrix4d T = o.T_lidar_body.matrix();
  Json j = Json::object();
  j["generator"] = "slam_mms_sim";
  j["scenario"] = o.oxts_drive_dir.empty() ? o.scenario : "oxts";
  j["oxts_drive_dir"] = o.oxts_drive_dir.string();
  j["oxts_start_s"] = o.oxts_start_s;
  if (!o.oxts_drive_dir.empty()) {
    j["oxts_truth"] = Json{{"follows_velocities", o.oxts_truth_follows_velocities},
                           {"position_sigma_m", o.oxts_truth_position_sigma_m}};
    Json spans = Json::array();
    for (const ImplausibleMotion& span : sim.implausible_motion()) {
      spans.push_back(Json{{"records", {span.first_record, span.last_record}},
                           {"from_s", span.from_s},
                           {"to_s", span.to_s},
                           {"max_sideways_mps", span.max_sideways_mps},
                           {"max_vertical_mps", span.max_vertical_mps}});
    }
    j["oxts_not_a_car"] = std::move(spans);
  }
  j["seed"] = o.seed;
  j["route_variant"] = o.route_variant;  // -1: the scenario's route alone
  j["num_route_variants"] = o.oxts_drive_dir.empty() ? NumRouteVariants(o.scenario) : 0;
  j["sensor_seed"] = sim.sensor_seed();
  j["duration_s"] = o.duration_s;
  j["lead_in_s"] = o.lead_in_s;
  j["drive"] = s.drive_name;
  j["date"] = o.date;
  j["drive_id"] = o.drive_id;
  j["world_frame"] =
      "local ENU (x east, y north, z up) about origin_wgs84 via GeographicLib LocalCartesian";
  j["origin_wgs84"] = Json{{"latitude_deg", o.origin_latitude_deg},
                           {"longitude_deg", o.origin_longitude_deg},
                           {"height_m", o.origin_height_m}};
  j["body_frame"] = "IMU/OXTS: x forward, y left, z up";
  Json t = Json::array();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) t.push_back(T(r, c));
  }
  j["T_lidar_body"] = std::move(t);  // the true one, which the scans are simulated with
  // What calib_imu_to_velo.txt holds: T_lidar_body with the calibration error on purpose.
  const Eigen::Matrix4d T_written = WrittenTLidarBody(o).matrix();
  Json tw = Json::array();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) tw.push_back(T_written(r, c));
  }
  j["T_lidar_body_written"] = std::move(tw);
  j["calib_error_rpy_deg"] = {o.calib_error_rpy_deg.x(), o.calib_error_rpy_deg.y(),
                              o.calib_error_rpy_deg.z()};
  j["calib_error_xyz_m"] = {o.calib_error_xyz_m.x(), o.calib_error_xyz_m.y(),
                            o.calib_error_xyz_m.z()};
  j["imu_mount_error_rpy_deg"] = {o.imu_mount_error_rpy_deg.x(), o.imu_mount_error_rpy_deg.y(),
                                  o.imu_mount_error_rpy_deg.z()};
  j["lidar_time_offset_s"] = o.lidar_time_offset_s;
  j["gravity_mps2"] = o.gravity_mps2;
  j["trajectory"] = Json{{"epoch_ns", tr.epoch().nanoseconds()},
                         {"start_s", tr.start_s()},
                         {"end_s", tr.end_s()},
                         {"first_scan_s", sim.first_scan_s()},
                         {"first_scan_stamp_ns", tr.ToTimestamp(sim.first_scan_s()).nanoseconds()},
                         {"knot_spacing_s", o.fit.knot_spacing_s},
                         {"position_sigma_m", o.fit.position_sigma_m},
                         {"angle_sigma_rad", o.fit.angle_sigma_rad},
                         {"accel_density", o.fit.accel_density},
                         {"angular_accel_density", o.fit.angular_accel_density}};
  const auto& st = sim.world().stats();
  j["world"] = Json{{"seed", w.seed},
                    {"corridor_m", w.corridor_m},
                    {"ground_cell_m", w.ground_cell_m},
                    {"body_height_above_road_m", w.body_height_above_road_m},
                    {"road_half_width_m", {w.road_half_width_min_m, w.road_half_width_max_m}},
                    {"sidewalk_width_m", {w.sidewalk_width_min_m, w.sidewalk_width_max_m}},
                    {"curb_height_m", w.curb_height_m},
                    {"building_height_m", {w.building_height_min_m, w.building_height_max_m}},
                    {"building_probability", w.building_probability},
                    {"pole_spacing_m", w.pole_spacing_m},
                    {"tree_probability", w.tree_probability},
                    {"parked_car_probability", w.parked_car_probability},
                    {"roughness_rms_m", Json{{"road", w.road_roughness_rms_m},
                                             {"sidewalk", w.sidewalk_roughness_rms_m},
                                             {"terrain", w.terrain_roughness_rms_m}}},
                    {"volumetric_vegetation", w.volumetric_vegetation},
                    {"foliage_mean_free_path_m", w.foliage_mean_free_path_m},
                    {"hedge_mean_free_path_m", w.hedge_mean_free_path_m},
                    {"hedge_probability", w.hedge_probability},
                    {"stats", Json{{"triangles", st.num_triangles},
                                   {"ground_triangles", st.num_ground_triangles},
                                   {"buildings", st.num_buildings},
                                   {"trees", st.num_trees},
                                   {"poles", st.num_poles},
                                   {"cars", st.num_cars},
                                   {"fences", st.num_fences},
                                   {"hedges", st.num_hedges},
                                   {"path_length_m", st.path_length_m}}}};
  Hdl64Lidar lidar(l);
  j["lidar"] = Json{{"model", "HDL-64E"},
                    {"elevations_deg", lidar.elevations_deg()},
                    {"firings_per_revolution", l.firings_per_revolution},
                    {"rotation_rate_hz", l.rotation_rate_hz},
                    {"direction", "clockwise from above, start/end at the rear"},
                    {"range_noise_sigma_m", l.range_noise_sigma_m},
                    {"min_range_m", l.min_range_m},
                    {"max_range_m", l.max_range_m},
                    {"min_cos_incidence", l.min_cos_incidence},
                    {"reflectance_noise_sigma", l.reflectance_noise_sigma},
                    {"elevation_bias_deg", l.elevation_bias_deg},
                    {"dropout_base", l.dropout_base},
                    {"dropout_far", l.dropout_far},
                    {"laser_elevation_sigma_deg", l.laser_elevation_sigma_deg},
                    {"laser_azimuth_sigma_deg", l.laser_azimuth_sigma_deg},
                    {"laser_range_offset_sigma_m", l.laser_range_offset_sigma_m},
                    {"laser_range_scale_sigma", l.laser_range_scale_sigma},
                    {"beam_divergence_rad", l.beam_divergence_rad},
                    {"mixed_pixel_max_separation_m", l.mixed_pixel_max_separation_m},
                    {"mixed_pixel_edge_threshold_m", l.mixed_pixel_edge_threshold_m},
                    {"motion_compensated", false}};
  {
    // The per-laser residuals the scans were simulated with (DriveSimulator passes this seed).
    Json errors = Json::array();
    bool any = false;
    for (const auto& e : lidar.LaserErrors(MixSeed(sim.sensor_seed(), 50))) {
      errors.push_back({e.elevation_deg, e.azimuth_deg, e.range_offset_m, e.range_scale});
      any = any || e.elevation_deg != 0.0 || e.azimuth_deg != 0.0 || e.range_offset_m != 0.0 ||
            e.range_scale != 0.0;
    }
    if (any) {
      j["lidar"]["laser_errors_columns"] = {"elevation_deg", "azimuth_deg", "range_offset_m",
                                            "range_scale"};
      j["lidar"]["laser_errors"] = std::move(errors);
    }
  }
  j["imu"] = Json{{"rate_hz", imu.rate_hz},
                  {"gyro_noise_density", imu.gyro_noise_density},
                  {"gyro_bias_instability", imu.gyro_bias_instability},
                  {"gyro_bias_tau_s", imu.gyro_bias_tau_s},
                  {"gyro_turn_on_bias_sigma", imu.gyro_turn_on_bias_sigma},
                  {"accel_noise_density", imu.accel_noise_density},
                  {"accel_bias_instability", imu.accel_bias_instability},
                  {"accel_bias_tau_s", imu.accel_bias_tau_s},
                  {"accel_turn_on_bias_sigma", imu.accel_turn_on_bias_sigma}};
  Json outages = Json::array();
  for (const auto& out : g.outages) {
    outages.push_back(Json{{"start_s", out.start_s}, {"duration_s", out.duration_s}});
  }
  j["gnss"] = Json{{"best_state", GnssStateName(g.best_state)},
                   {"sigma_fixed_m", {g.sigma_fixed_h_m, g.sigma_fixed_v_m}},
                   {"sigma_float_m", {g.sigma_float_h_m, g.sigma_float_v_m}},
                   {"sigma_sps_m", {g.sigma_sps_h_m, g.sigma_sps_v_m}},
                   {"multipath_rate_hz", g.multipath_rate_hz},
                   {"multipath_sigma_m", g.multipath_sigma_m},
                   {"urban_canyon_scale", g.urban_canyon_scale},
                   {"blockage_thresholds", {g.blockage_float, g.blockage_sps, g.blockage_none}},
                   {"outages_relative_to_first_scan", std::move(outages)},
                   {"antenna_above_imu_m", 0.75}};
  j["ins"] = Json{{"roll_pitch_sigma_rad", o.ins_roll_pitch_sigma_rad},
                  {"yaw_sigma_rad", o.ins_yaw_sigma_rad},
                  {"velocity_sigma_mps", o.ins_velocity_sigma_mps},
                  {"oxts_inertial_lag_s", o.oxts_inertial_lag_s}};
  j["scene_cloud_voxel_m"] = o.scene_cloud_voxel_m;
  j["summary"] = Json{{"scans", s.num_scans},
                      {"points", s.num_points},
                      {"imu_records", s.num_imu_records},
                      {"scene_points", s.num_scene_points},
                      {"simulated_seconds", s.simulated_seconds},
                      {"path_length_m", s.path_length_m},
                      {"gnss_fraction", Json{{"rtk_fixed", s.fraction_fixed},
                                             {"rtk_float", s.fraction_float},
                                             {"sps", s.fraction_sps},
                                             {"none", s.fraction_none}}}};
  std::ofstream f(file, std::ios::binary | std::ios::trunc);
  if (!f) return InternalError("cannot write " + file.string());
  // Doubles read back exactly; NaN/inf (none expected) would be null.
  f << j.dump(2, ' ', false, Json::error_handler_t::replace) << "\n";
  if (!f) return InternalError("write failed: " + file.string());
  return OkStatus();
}

}  // namespace slam_mms::sim
