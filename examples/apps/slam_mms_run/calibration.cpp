#include "slam_mms_run/calibration.hpp"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/io/kitti_calibration.hpp"

namespace slam_mms::app {
namespace {

using Json = nlohmann::ordered_json;
constexpr double kDeg = 180.0 / M_PI;

Json Matrix4(const Eigen::Isometry3d& T) {
  Json rows = Json::array();
  for (int r = 0; r < 4; ++r) {
    Json row = Json::array();
    for (int c = 0; c < 4; ++c) row.push_back(T.matrix()(r, c));
    rows.push_back(std::move(row));
  }
  return rows;
}

Json Vec(const Eigen::Vector3d& v, double scale = 1.0) {
  return Json::array({v(0) * scale, v(1) * scale, v(2) * scale});
}

}  // namespace

std::string CalibrationJson(const ExtrinsicCalibration& c, const std::string& file_name,
                            double input_time_offset_s) {
  Json j = Json::object();
  j["T_body_lidar_initial"] = Matrix4(c.T_body_lidar_initial);
  j["T_body_lidar_estimated"] = Matrix4(c.T_body_lidar_estimated);
  j["correction_rpy_deg"] = Vec(c.correction_rpy_rad, kDeg);
  j["correction_xyz_m"] = Vec(c.correction_xyz_m);
  j["time_offset_s"] = input_time_offset_s + c.time_offset_s;
  j["time_offset_initial_s"] = input_time_offset_s + c.time_offset_initial_s;
  j["sigma_rpy_deg"] = Vec(c.sigma_rpy_rad, kDeg);
  j["sigma_xyz_m"] = Vec(c.sigma_xyz_m);
  j["sigma_time_offset_s"] = c.sigma_time_s;
  Json obs = Json::object(), applied = Json::object(), significance = Json::object();
  for (int i = 0; i < 7; ++i) {
    obs[ExtrinsicParameterName(i)] = c.observable[i];
    applied[ExtrinsicParameterName(i)] = c.applied[i];
    significance[ExtrinsicParameterName(i)] = c.significance(i);
  }
  j["observable"] = std::move(obs);
  j["applied"] = std::move(applied);
  j["significance"] = std::move(significance);
  j["attitude_reference"] = c.attitude_reference;
  j["attitude_reference_sigma_deg"] = Vec(c.pos_attitude_sigma_rad, kDeg);
  j["travel_direction_correction_deg"] = Vec(c.travel_correction_rad, kDeg);
  j["travel_direction_scans"] = c.travel_samples;
  Json formal = Json::array(), jack = Json::array(), sys = Json::array();
  for (int i = 0; i < 7; ++i) {
    const double s = i < 3 ? kDeg : 1.0;  // deg, m, s
    formal.push_back(c.formal_sigma(i) * s);
    jack.push_back(c.jackknife_sigma(i) * s);
    sys.push_back(c.systematic_sigma(i) * s);
  }
  j["data_sigma"] = Json{{"order", "roll_deg pitch_deg yaw_deg x_m y_m z_m time_offset_s"},
                         {"formal", std::move(formal)},
                         {"jackknife", std::move(jack)},
                         {"systematic", std::move(sys)}};
  j["scans_used"] = c.scans_used;
  j["scans_skipped_pos"] = c.scans_skipped_pos;
  j["scans_skipped_unreadable"] = c.scans_skipped_unreadable;
  j["residuals"] = c.residuals;
  j["rounds"] = c.rounds;
  j["converged"] = c.converged;
  j["rms_initial_m"] = c.rms_initial_m;
  j["rms_final_m"] = c.rms_final_m;
  j["total_heading_change_deg"] = c.total_heading_change_rad * kDeg;
  j["pos_drift"] = Json{{"knots", c.pos_drift_knots},
                        {"rate_rms_mps", Vec(c.pos_drift_rate_rms_mps)},
                        {"max_m", c.pos_drift_max_m}};
  j["wall_s"] = c.wall_s;
  j["calibration_file"] = file_name;
  return j.dump();
}

StatusOr<RunCalibration> CalibrateRunExtrinsics(const DriveReader& reader,
                                                const MappingSystem::Options& options,
                                                const ExtrinsicCalibrationOptions& calibration,
                                                const std::filesystem::path& out_dir,
                                                double input_time_offset_s,
                                                const std::atomic<bool>* stop) {
  std::printf("[calibration] offline POS of the drive, then the LiDAR extrinsic against it\n");
  std::fflush(stdout);
  RunCalibration out;
  SLAM_MMS_ASSIGN_OR_RETURN(out.result,
                            CalibrateDriveExtrinsics(reader, options, calibration, stop));
  const ExtrinsicCalibration& c = out.result;
  out.extrinsics.T_body_lidar = c.T_body_lidar_estimated;
  out.extrinsics.lidar_time_offset_s = c.time_offset_s;
  const std::string name = "calib_imu_to_velo_estimated.txt";
  out.file = out_dir / name;
  DriveExtrinsics written = out.extrinsics;
  written.lidar_time_offset_s += input_time_offset_s;
  SLAM_MMS_RETURN_IF_ERROR(
      WriteKittiImuToVelo(written, out.file, "slam_mms_run --calibrate-extrinsics"));
  out.json = CalibrationJson(c, name, input_time_offset_s);
  std::string unobservable, insignificant;
  for (int i = 0; i < 7; ++i) {
    if (!c.observable[i]) unobservable += std::string(" ") + ExtrinsicParameterName(i);
    if (c.observable[i] && !c.applied[i]) {
      insignificant += std::string(" ") + ExtrinsicParameterName(i);
    }
  }
  std::printf(
      "[calibration] %d scans, %zu residuals, rms %.4f -> %.4f m, %.1f s\n"
      "[calibration] correction rpy [%.4f %.4f %.4f] deg (sigma [%.4f %.4f %.4f]), xyz "
      "[%.4f %.4f %.4f] m (sigma [%.4f %.4f %.4f]), time offset %.4f s (sigma %.4f)\n"
      "[calibration] held at the file's values: not observable in this drive:%s; within %.0f "
      "sigma of the file:%s\n",
      c.scans_used, c.residuals, c.rms_initial_m, c.rms_final_m, c.wall_s,
      c.correction_rpy_rad(0) * kDeg, c.correction_rpy_rad(1) * kDeg,
      c.correction_rpy_rad(2) * kDeg, c.sigma_rpy_rad(0) * kDeg, c.sigma_rpy_rad(1) * kDeg,
      c.sigma_rpy_rad(2) * kDeg, c.correction_xyz_m(0), c.correction_xyz_m(1),
      c.correction_xyz_m(2), c.sigma_xyz_m(0), c.sigma_xyz_m(1), c.sigma_xyz_m(2),
      written.lidar_time_offset_s, c.sigma_time_s,
      unobservable.empty() ? " none" : unobservable.c_str(), calibration.min_significance,
      insignificant.empty() ? " none" : insignificant.c_str());
  std::fflush(stdout);
  return out;
}

}  // namespace slam_mms::app
