#include "slam_mms/eval/oxts_reference.hpp"

#include <GeographicLib/LocalCartesian.hpp>
#include <cmath>
#include <string>

#include "slam_mms/core/geodesy.hpp"
#include "slam_mms/io/oxts_record.hpp"

namespace slam_mms::eval {

namespace {

std::string RecordName(const StampedOxts& r, size_t i) {
  return "OXTS record " + std::to_string(i) + " (file " + std::to_string(r.index) + ")";
}

}  // namespace

StatusOr<Trajectory> OxtsTrajectory(const std::vector<StampedOxts>& records,
                                    const GeodeticPoint& run_origin,
                                    const OxtsTrajectoryOptions& options) {
  if (records.size() < 2) {
    return InvalidArgumentError("OxtsTrajectory: " + std::to_string(records.size()) +
                                " records; a trajectory needs at least 2");
  }
  if (!(options.max_gap_s > 0.0)) {
    return InvalidArgumentError("OxtsTrajectoryOptions::max_gap_s = " +
                                std::to_string(options.max_gap_s) + "; must be > 0");
  }
  const GeographicLib::LocalCartesian run_lc(run_origin.latitude_deg, run_origin.longitude_deg,
                                             run_origin.height_m);
  const Eigen::Matrix3d R_run_ecef =
      R_ecef_enu(run_origin.latitude_deg, run_origin.longitude_deg).transpose();
  const bool integrate = options.positions == OxtsPositions::kVelocityIntegrated;
  Trajectory out;
  Eigen::Vector3d p_run = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_prev = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < records.size(); ++i) {
    const StampedOxts& r = records[i];
    const OxtsRecord& o = r.record;
    const Eigen::Vector3d v_local(o.ve, o.vn, o.vu);
    if (!std::isfinite(o.lat_deg) || !std::isfinite(o.lon_deg) || !std::isfinite(o.alt_m) ||
        !std::isfinite(o.roll_rad) || !std::isfinite(o.pitch_rad) || !std::isfinite(o.yaw_rad) ||
        (integrate && !v_local.allFinite())) {
      return DataLossError(RecordName(r, i) +
                           ": a position, attitude or velocity field is not "
                           "finite");
    }
    // OXTS attitude and velocity are relative to the local level (ENU) frame at the record.
    const Eigen::Matrix3d R_run_local = R_run_ecef * R_ecef_enu(o.lat_deg, o.lon_deg);
    const Eigen::Vector3d v_run = R_run_local * v_local;
    if (i == 0 || !integrate) {
      run_lc.Forward(o.lat_deg, o.lon_deg, o.alt_m, p_run.x(), p_run.y(), p_run.z());
    } else {
      const double dt = r.stamp.SecondsSince(records[i - 1].stamp);
      if (!(dt > 0.0) || dt > options.max_gap_s) {
        return DataLossError(RecordName(r, i) + ": " + std::to_string(dt) +
                             " s after the previous record; the velocity integral needs steps in "
                             "(0, " +
                             std::to_string(options.max_gap_s) + "] s");
      }
      p_run += 0.5 * (v_prev + v_run) * dt;
    }
    v_prev = v_run;
    Eigen::Isometry3d T_run_body = Eigen::Isometry3d::Identity();
    T_run_body.linear() = R_run_local * OxtsAttitude(o);
    T_run_body.translation() = p_run;
    const Status s = out.Add(r.stamp, T_run_body);
    if (!s.ok()) return DataLossError(RecordName(r, i) + ": " + s.message());
  }
  return out;
}

StatusOr<IncrementAgreement> CompareIncrements(const Trajectory& track, const Trajectory& reference,
                                               double window_s, double min_distance_m) {
  if (!(window_s > 0.0) || !(min_distance_m > 0.0)) {
    return InvalidArgumentError("CompareIncrements: window_s = " + std::to_string(window_s) +
                                ", min_distance_m = " + std::to_string(min_distance_m) +
                                "; both must be > 0");
  }
  IncrementAgreement a;
  a.window_s = window_s;
  double sum_sq = 0.0, sum_along = 0.0, sum_along_sq = 0.0, sum_cross = 0.0, sum_cross_sq = 0.0;
  double sum_vert_sq = 0.0, sum_dist = 0.0;
  const std::vector<StampedPose>& poses = track.poses();
  size_t j = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < poses.size() && poses[j].stamp.SecondsSince(poses[i].stamp) < window_s) ++j;
    if (j >= poses.size()) break;
    const StatusOr<Eigen::Isometry3d> r0 = reference.Interpolate(poses[i].stamp);
    const StatusOr<Eigen::Isometry3d> r1 = reference.Interpolate(poses[j].stamp);
    if (!r0.ok() || !r1.ok()) continue;  // outside the reference's span
    const Eigen::Vector3d d_ref = r1->translation() - r0->translation();
    const Eigen::Vector3d d_track =
        poses[j].T_world_body.translation() - poses[i].T_world_body.translation();
    const double dist = d_ref.head<2>().norm();
    if (dist < min_distance_m) continue;
    const Eigen::Vector2d u = d_ref.head<2>() / dist;
    const Eigen::Vector3d diff = d_track - d_ref;
    const double along = u.dot(diff.head<2>()) / dist * 100.0;
    const double cross = (u.x() * diff.y() - u.y() * diff.x()) / dist * 100.0;
    const double vert = diff.z() / dist * 100.0;
    ++a.windows;
    sum_dist += dist;
    sum_sq += along * along + cross * cross;
    sum_along += along;
    sum_along_sq += along * along;
    sum_cross += cross;
    sum_cross_sq += cross * cross;
    sum_vert_sq += vert * vert;
  }
  if (a.windows == 0) {
    return FailedPreconditionError(
        "CompareIncrements: no window of " + std::to_string(window_s) + " s covers at least " +
        std::to_string(min_distance_m) +
        " m inside both trajectories (standing, too short, or no overlap in time)");
  }
  const double n = static_cast<double>(a.windows);
  a.mean_distance_m = sum_dist / n;
  a.rms_pct = std::sqrt(sum_sq / n);
  a.along_mean_pct = sum_along / n;
  a.along_std_pct =
      std::sqrt(std::max(0.0, sum_along_sq / n - a.along_mean_pct * a.along_mean_pct));
  a.cross_mean_pct = sum_cross / n;
  a.cross_std_pct =
      std::sqrt(std::max(0.0, sum_cross_sq / n - a.cross_mean_pct * a.cross_mean_pct));
  a.vertical_rms_pct = std::sqrt(sum_vert_sq / n);
  return a;
}

}  // namespace slam_mms::eval
