#include "slam_mms/drive/extrinsic_calibration_options.hpp"

#include <string>

#include "core/option_error.hpp"

namespace slam_mms {
namespace {

Status FieldError(const std::string& field, double value, const std::string& rule) {
  return internal::OptionError("ExtrinsicCalibrationOptions", field, value, rule);
}

}  // namespace

Status ExtrinsicCalibrationOptions::Validate() const {
  if (max_scans < 10) return FieldError("max_scans", max_scans, "must be >= 10");
  if (!(min_range_m >= 0.0 && max_range_m > min_range_m))
    return FieldError("max_range_m", max_range_m, "must be > min_range_m >= 0");
  if (!(voxel_m > 0.0)) return FieldError("voxel_m", voxel_m, "must be > 0");
  if (max_points_per_scan < 100)
    return FieldError("max_points_per_scan", max_points_per_scan, "must be >= 100");
  if (query_stride < 1) return FieldError("query_stride", query_stride, "must be >= 1");
  for (double s : partner_separations_s) {
    if (!(s > 0.0)) return FieldError("partner_separations_s", s, "each must be > 0");
  }
  if (partners_per_point < 1)
    return FieldError("partners_per_point", partners_per_point, "must be >= 1");
  if (num_neighbours < 4) return FieldError("num_neighbours", num_neighbours, "must be >= 4");
  if (!(max_neighbour_distance_m > 0.0))
    return FieldError("max_neighbour_distance_m", max_neighbour_distance_m, "must be > 0");
  if (!(max_plane_thickness_m > 0.0))
    return FieldError("max_plane_thickness_m", max_plane_thickness_m, "must be > 0");
  if (!(final_gate_m > 0.0 && initial_gate_m >= final_gate_m))
    return FieldError("initial_gate_m", initial_gate_m, "must be >= final_gate_m > 0");
  if (!(huber_m > 0.0)) return FieldError("huber_m", huber_m, "must be > 0");
  if (max_rounds < 1) return FieldError("max_rounds", max_rounds, "must be >= 1");
  if (gauss_newton_steps_per_round < 1)
    return FieldError("gauss_newton_steps_per_round", gauss_newton_steps_per_round, "must be >= 1");
  if (!(max_pos_sigma_m > 0.0))
    return FieldError("max_pos_sigma_m", max_pos_sigma_m, "must be > 0");
  if (!(travel_min_speed_mps > 0.0))
    return FieldError("travel_min_speed_mps", travel_min_speed_mps, "must be > 0");
  if (!(travel_max_yaw_rate_radps > 0.0))
    return FieldError("travel_max_yaw_rate_radps", travel_max_yaw_rate_radps, "must be > 0");
  if (!(travel_sigma_rad >= 0.0))
    return FieldError("travel_sigma_rad", travel_sigma_rad, "must be >= 0");
  if (!(max_pos_sigma_ratio >= 1.0))
    return FieldError("max_pos_sigma_ratio", max_pos_sigma_ratio, "must be >= 1");
  if (!(prior_sigma_rpy_rad.minCoeff() > 0.0 && prior_sigma_xyz_m.minCoeff() > 0.0 &&
        prior_sigma_time_s > 0.0) ||
      !prior_sigma_rpy_rad.allFinite() || !prior_sigma_xyz_m.allFinite())
    return FieldError("prior_sigma_*", prior_sigma_time_s, "every prior sigma must be > 0, finite");
  if (!(systematic_error_m >= 0.0))
    return FieldError("systematic_error_m", systematic_error_m, "must be >= 0");
  if (!(min_prior_reduction >= 1.0))
    return FieldError("min_prior_reduction", min_prior_reduction, "must be >= 1");
  if (!(pos_drift_knot_interval_s > 0.0))
    return FieldError("pos_drift_knot_interval_s", pos_drift_knot_interval_s, "must be > 0");
  if (!(pos_max_velocity_error_mps > 0.0))
    return FieldError("pos_max_velocity_error_mps", pos_max_velocity_error_mps, "must be > 0");
  if (!(pos_error_correlation_s > 0.0))
    return FieldError("pos_error_correlation_s", pos_error_correlation_s, "must be > 0");
  if (!(min_significance >= 0.0))
    return FieldError("min_significance", min_significance, "must be >= 0");
  if (jackknife_blocks < 2) return FieldError("jackknife_blocks", jackknife_blocks, "must be >= 2");
  return OkStatus();
}

}  // namespace slam_mms
