#include "slam_mms/eval/ground_truth.hpp"

#include <GeographicLib/LocalCartesian.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "slam_mms/core/geodesy.hpp"
#include "slam_mms/eval/oxts_reference.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/io/oxts_record.hpp"
#include "slam_mms/io/trajectory_io.hpp"

namespace slam_mms::eval {

StatusOr<GeodeticPoint> ReadScenarioOrigin(const std::filesystem::path& scenario_json) {
  std::ifstream in(scenario_json);
  if (!in) return NotFoundError(scenario_json.string() + ": cannot open");
  const std::string file = scenario_json.string();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    return DataLossError(file + ": not valid JSON: " + e.what());  // names the byte and token
  }
  if (!j.is_object() || !j.contains("origin_wgs84") || !j["origin_wgs84"].is_object()) {
    return DataLossError(file + ": no object 'origin_wgs84'");
  }
  const nlohmann::json& o = j["origin_wgs84"];
  GeodeticPoint origin;
  for (const auto& [key, value] :
       {std::pair<const char*, double*>{"latitude_deg", &origin.latitude_deg},
        {"longitude_deg", &origin.longitude_deg},
        {"height_m", &origin.height_m}}) {
    if (!o.contains(key)) return DataLossError(file + ": origin_wgs84 has no field '" + key + "'");
    if (!o[key].is_number() || !std::isfinite(o[key].get<double>())) {
      return DataLossError(file + ": origin_wgs84." + key + " is not a finite number");
    }
    *value = o[key].get<double>();
  }
  if (std::abs(origin.latitude_deg) > 90.0 || std::abs(origin.longitude_deg) > 180.0) {
    return DataLossError(file + ": origin_wgs84 outside the WGS-84 range");
  }
  return origin;
}

bool HasSimulatorGroundTruth(const std::filesystem::path& drive_dir) {
  const std::filesystem::path gt = drive_dir / "ground_truth";
  std::error_code ec;
  return std::filesystem::exists(gt / "scenario.json", ec) &&
         std::filesystem::exists(gt / "poses_100hz.tum", ec);
}

namespace {

StatusOr<GroundTruth> LoadSimulator(const std::filesystem::path& drive_dir,
                                    const GeodeticPoint& run_origin) {
  const std::filesystem::path dir = drive_dir / "ground_truth";
  SLAM_MMS_ASSIGN_OR_RETURN(const GeodeticPoint sim_origin,
                            ReadScenarioOrigin(dir / "scenario.json"));
  SLAM_MMS_ASSIGN_OR_RETURN(Trajectory poses, ReadTrajectoryTum(dir / "poses_100hz.tum"));
  // The 100 Hz poses plus the exact poses at every scan start, so the interpolation at scan starts
  // (where the estimates are) is exact.
  std::vector<StampedPose> all = poses.poses();
  std::error_code ec;
  if (std::filesystem::exists(dir / "scan_start.tum", ec)) {
    SLAM_MMS_ASSIGN_OR_RETURN(Trajectory starts, ReadTrajectoryTum(dir / "scan_start.tum"));
    all.insert(all.end(), starts.poses().begin(), starts.poses().end());
  }
  std::stable_sort(all.begin(), all.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; });

  const GeographicLib::LocalCartesian sim_lc(sim_origin.latitude_deg, sim_origin.longitude_deg,
                                             sim_origin.height_m);
  const GeographicLib::LocalCartesian run_lc(run_origin.latitude_deg, run_origin.longitude_deg,
                                             run_origin.height_m);
  // R_run_sim = R_run_ecef * R_ecef_sim: both world frames are Cartesian ENU frames.
  const Eigen::Matrix3d R_run_sim =
      R_ecef_enu(run_origin.latitude_deg, run_origin.longitude_deg).transpose() *
      R_ecef_enu(sim_origin.latitude_deg, sim_origin.longitude_deg);

  GroundTruth gt;
  gt.kind = "simulator";
  gt.source = dir;
  if (std::filesystem::exists(dir / "scene_points.ply", ec))
    gt.scene_map = dir / "scene_points.ply";
  for (size_t i = 0; i < all.size(); ++i) {
    if (i > 0 && all[i].stamp == all[i - 1].stamp) continue;  // scan start on a 100 Hz record
    const Eigen::Vector3d& p_sim = all[i].T_world_body.translation();
    double lat = 0, lon = 0, h = 0;
    sim_lc.Reverse(p_sim.x(), p_sim.y(), p_sim.z(), lat, lon, h);
    Eigen::Vector3d p_run;
    run_lc.Forward(lat, lon, h, p_run.x(), p_run.y(), p_run.z());
    Eigen::Isometry3d T_run_body = Eigen::Isometry3d::Identity();
    T_run_body.linear() = R_run_sim * all[i].T_world_body.linear();
    T_run_body.translation() = p_run;
    SLAM_MMS_RETURN_IF_ERROR(gt.T_world_body.Add(all[i].stamp, T_run_body));
  }
  if (gt.T_world_body.size() < 2) {
    return DataLossError((dir / "poses_100hz.tum").string() + ": fewer than 2 poses");
  }
  return gt;
}

StatusOr<GroundTruth> LoadOxts(const KittiRawReader& reader, const GeodeticPoint& run_origin,
                               OxtsPositions positions) {
  // The denser stream when the drive has 100 Hz records.
  const std::vector<StampedOxts>& records =
      reader.HasImu100Hz() ? reader.ImuOxtsRecords() : reader.OxtsRecords();
  if (records.size() < 2) {
    return NotFoundError(
        reader.drive_dir().string() +
        ": no ground truth (no ground_truth/ folder and fewer than 2 OXTS records)");
  }
  GroundTruth gt;
  gt.kind = positions == OxtsPositions::kRecorded ? "oxts" : "oxts_velocity";
  gt.source = reader.drive_dir() / (reader.HasImu100Hz() ? "oxts_100hz" : "oxts");
  OxtsTrajectoryOptions options;
  options.positions = positions;
  StatusOr<Trajectory> t = OxtsTrajectory(records, run_origin, options);
  if (!t.ok()) return t.status().WithContext(gt.source.string());
  gt.T_world_body = std::move(t).value();
  return gt;
}

}  // namespace

StatusOr<GroundTruth> LoadGroundTruth(const std::filesystem::path& gt_dir,
                                      const DriveReader& reader, const GeodeticPoint& run_origin) {
  if (HasSimulatorGroundTruth(gt_dir)) return LoadSimulator(gt_dir, run_origin);
  if (const auto* kitti = dynamic_cast<const KittiDriveReader*>(&reader.Underlying())) {
    return LoadOxts(kitti->kitti(), run_origin, OxtsPositions::kRecorded);
  }
  return NotFoundError(reader.Describe() + ": no ground truth (no " +
                       (gt_dir / "ground_truth").string() + " folder)");
}

StatusOr<GroundTruth> LoadOxtsGroundTruth(const DriveReader& reader,
                                          const GeodeticPoint& run_origin,
                                          OxtsPositions positions) {
  if (const auto* kitti = dynamic_cast<const KittiDriveReader*>(&reader.Underlying())) {
    return LoadOxts(kitti->kitti(), run_origin, positions);
  }
  return NotFoundError(reader.Describe() + ": no OXTS records (not a KITTI raw drive)");
}

}  // namespace slam_mms::eval
