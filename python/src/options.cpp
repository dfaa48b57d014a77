// Options bindings: every field of MappingSystem::Options and of the Options it nests, with the C++
// defaults (a default-constructed Python object is a default-constructed C++ struct). Nested
// options are attributes holding objects that may be modified in place
// (`options.localizer.icp.max_iterations = 10`). Each class has `validate()`, which raises
// ValueError with the C++ message naming the field and its rule, and `_fields` (the field names,
// used by the Python package for repr() and to_dict()).

#include "common.hpp"
#include "slam_mms/backend/sliding_window_options.hpp"
#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"
#include "slam_mms/ins/ins_filter.hpp"
#include "slam_mms/pipeline/deskew_options.hpp"
#include "slam_mms/pipeline/dynamic_object_options.hpp"
#include "slam_mms/pipeline/level2_options.hpp"
#include "slam_mms/pipeline/localizer.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"
#include "slam_mms/registration/registration_options.hpp"
#include "slam_mms/surfel/range_projection.hpp"
#include "slam_mms/surfel/surfel_map.hpp"
#include "slam_mms/surfel/surfel_renderer.hpp"

namespace slam_mms::python {
namespace {

// A py::class_ for an Options struct: default constructor, keyword constructor through
// setattr, validate(), copy, and the list of field names.
template <typename T>
class OptionsClass {
 public:
  OptionsClass(py::handle scope, const char* name, const char* doc) : cls_(scope, name, doc) {
    cls_.def(py::init<>());
    cls_.def("__copy__", [](const T& o) { return T(o); });
    cls_.def(
        "__deepcopy__", [](const T& o, py::dict) { return T(o); }, py::arg("memo"));
    cls_.def(
        "copy", [](const T& o) { return T(o); }, "A deep copy.");
  }
  template <typename D>
  OptionsClass& Field(const char* name, D T::*member, const char* doc) {
    cls_.def_readwrite(name, member, doc);
    fields_.append(name);
    return *this;
  }
  template <typename G, typename S>
  OptionsClass& Property(const char* name, G&& get, S&& set, const char* doc) {
    cls_.def_property(name, std::forward<G>(get), std::forward<S>(set), doc);
    fields_.append(name);
    return *this;
  }
  OptionsClass& Validated() {
    cls_.def(
        "validate", [](const T& o) { ThrowIfError(o.Validate()); },
        "Raises ValueError naming the first bad field and its rule.");
    return *this;
  }
  py::class_<T>& Done() {
    cls_.attr("_fields") = py::tuple(fields_);
    return cls_;
  }

 private:
  py::class_<T> cls_;
  py::list fields_;
};

}  // namespace

void RegisterOptions(py::module_& m) {
  py::enum_<MappingMode>(m, "MappingMode",
                         "FULL: the SLAM-integrated system; GNSS_INS: scans at the forward POS "
                         "poses; GNSS_INS_SMOOTHED: scans at the forward-backward smoothed POS "
                         "(offline: run_drive only, not MappingSystem); LIDAR_ONLY: the SuMa-like "
                         "baseline.")
      .value("FULL", MappingMode::kFull)
      .value("GNSS_INS", MappingMode::kGnssIns)
      .value("GNSS_INS_SMOOTHED", MappingMode::kGnssInsSmoothed)
      .value("LIDAR_ONLY", MappingMode::kLidarOnly);
  py::enum_<PosWorkflow>(m, "PosWorkflow",
                         "The POS `full` runs on in run_drive: FORWARD (streaming, the default) or "
                         "SMOOTHED (the whole drive smoothed first, offline).")
      .value("FORWARD", PosWorkflow::kForward)
      .value("SMOOTHED", PosWorkflow::kSmoothed);
  m.def(
      "parse_mapping_mode",
      [](const std::string& name) {
        MappingMode mode = MappingMode::kFull;
        if (!ParseMappingMode(name, &mode)) {
          throw py::value_error("mode = '" + name +
                                "'; must be full, gnss_ins, gnss_ins_smoothed or lidar_only");
        }
        return mode;
      },
      py::arg("name"));
  m.def("mapping_mode_name", [](MappingMode mode) { return std::string(MappingModeName(mode)); });
  py::enum_<SurfelRendererBackend>(m, "SurfelRendererBackend")
      .value("AUTO", SurfelRendererBackend::kAuto)
      .value("CPU", SurfelRendererBackend::kCpu)
      .value("EGL", SurfelRendererBackend::kEgl);
  py::enum_<WindowExitMode>(m, "WindowExitMode")
      .value("MARGINALIZE", WindowExitMode::kMarginalize)
      .value("FIX", WindowExitMode::kFix);
  py::enum_<WindowInconsistencyAction>(m, "InconsistencyAction")
      .value("REJECT", WindowInconsistencyAction::kReject)
      .value("DOWN_WEIGHT", WindowInconsistencyAction::kDownWeight);

  using GP = GnssPrior::Options;
  OptionsClass<GP>(m, "GnssPriorOptions", "GnssPrior::Options: GNSS decisions and lever arm.")
      .Field("t_body_antenna", &GP::t_body_antenna, "Lever arm in body [m] (3,).")
      .Field("sigma_floor_horizontal_m", &GP::sigma_floor_horizontal_m, "[m]")
      .Field("sigma_floor_vertical_m", &GP::sigma_floor_vertical_m, "[m]")
      .Field("max_sigma_horizontal_m", &GP::max_sigma_horizontal_m,
             "Fixes reporting more: rejected [m]")
      .Field("min_fix_type", &GP::min_fix_type, "Below: rejected.")
      .Field("full_weight_fix_type", &GP::full_weight_fix_type, "Below: down-weighted.")
      .Field("downweight_variance_factor", &GP::downweight_variance_factor, ">= 1")
      .Field("innovation_downweight_chi2", &GP::innovation_downweight_chi2, "3 dof")
      .Field("innovation_reject_chi2", &GP::innovation_reject_chi2, "3 dof")
      .Field("max_rejection_streak_s", &GP::max_rejection_streak_s, "[s]")
      .Field("max_speed_mps", &GP::max_speed_mps, "[m/s]")
      .Field("outage_timeout_s", &GP::outage_timeout_s, "[s]")
      .Validated()
      .Done();

  using GEM = InsFilter::Options::GnssErrorModel;
  OptionsClass<GEM>(m, "GnssErrorModel",
                    "Time-correlated GNSS error of one solution type (InsFilter, Level2Options).")
      .Field("correlated_fraction", &GEM::correlated_fraction,
             "Share of the fix variance that is a Gauss-Markov bias, [0, 1)")
      .Field("correlation_time_s", &GEM::correlation_time_s, "[s]")
      .Done();

  using IO = InsFilter::Options;
  OptionsClass<IO>(m, "InsOptions", "InsFilter::Options: the POS (error-state EKF).")
      .Field("gyro_noise_density", &IO::gyro_noise_density, "[rad/s/sqrt(Hz)]")
      .Field("accel_noise_density", &IO::accel_noise_density, "[m/s^2/sqrt(Hz)]")
      .Field("gyro_bias_random_walk", &IO::gyro_bias_random_walk, "[rad/s^2/sqrt(Hz)]")
      .Field("accel_bias_random_walk", &IO::accel_bias_random_walk, "[m/s^3/sqrt(Hz)]")
      .Field("gravity_mps2", &IO::gravity_mps2, "<= 0: Somigliana at the origin [m/s^2]")
      .Field("init_sigma_position_m", &IO::init_sigma_position_m, "[m]")
      .Field("init_sigma_velocity_mps", &IO::init_sigma_velocity_mps, "[m/s]")
      .Field("init_sigma_roll_pitch_rad", &IO::init_sigma_roll_pitch_rad, "[rad]")
      .Field("init_sigma_yaw_rad", &IO::init_sigma_yaw_rad, "[rad]")
      .Field("init_sigma_accel_bias_mps2", &IO::init_sigma_accel_bias_mps2, "[m/s^2]")
      .Field("init_sigma_gyro_bias_radps", &IO::init_sigma_gyro_bias_radps, "[rad/s]")
      .Field("use_stated_attitude_sigma", &IO::use_stated_attitude_sigma,
             "start from the initial attitude's stated accuracy where its source gives one")
      .Field("max_imu_gap_s", &IO::max_imu_gap_s, "[s]")
      .Field("max_fix_latency_s", &IO::max_fix_latency_s, "[s]")
      .Field("max_extrapolation_s", &IO::max_extrapolation_s, "[s]")
      .Field("history_s", &IO::history_s, "[s]")
      .Field("gnss_error_rtk_fixed", &IO::gnss_error_rtk_fixed,
             "GnssErrorModel of RTK-fixed solutions (white by default).")
      .Field("gnss_error_rtk_float", &IO::gnss_error_rtk_float, "GnssErrorModel of float ones.")
      .Field("gnss_error_code", &IO::gnss_error_code,
             "GnssErrorModel of single-point and differential ones.")
      .Field("zupt", &IO::zupt, "Zero-velocity updates while standing")
      .Field("zupt_window_s", &IO::zupt_window_s, "[s]")
      .Field("zupt_max_gyro_radps", &IO::zupt_max_gyro_radps, "[rad/s]")
      .Field("zupt_max_accel_mps2", &IO::zupt_max_accel_mps2,
             "Max gravity-compensated acceleration [m/s^2]")
      .Field("zupt_max_speed_mps", &IO::zupt_max_speed_mps, "[m/s]")
      .Field("zupt_sigma_mps", &IO::zupt_sigma_mps, "[m/s]")
      .Field("zupt_interval_s", &IO::zupt_interval_s, "[s]")
      .Field("nhc_sigma_mps", &IO::nhc_sigma_mps, "Non-holonomic constraint sigma, 0: off [m/s]")
      .Field("nhc_min_speed_mps", &IO::nhc_min_speed_mps, "[m/s]")
      .Field("nhc_lateral_correlation_time_s", &IO::nhc_lateral_correlation_time_s,
             "Correlation time of the constraint's lateral errors, 0: white [s]")
      .Field("nhc_vertical_correlation_time_s", &IO::nhc_vertical_correlation_time_s,
             "Correlation time of the constraint's vertical errors, 0: white [s]")
      .Field("vehicle_pitch_misalignment_rad", &IO::vehicle_pitch_misalignment_rad,
             "IMU-to-vehicle misalignment the constraint starts from: pitch about body y [rad]")
      .Field("vehicle_yaw_misalignment_rad", &IO::vehicle_yaw_misalignment_rad,
             "IMU-to-vehicle misalignment: yaw about body z [rad]")
      .Field("vehicle_misalignment_sigma_rad", &IO::vehicle_misalignment_sigma_rad,
             "1-sigma of the misalignment: > 0 estimates it while the constraint is on, 0: exact "
             "[rad]")
      .Field("vehicle_lever_arm_m", &IO::vehicle_lever_arm_m,
             "The IMU's distance ahead of the vehicle's rear axle (its non-holonomic point) [m]")
      .Field("vehicle_lever_arm_sigma_m", &IO::vehicle_lever_arm_sigma_m,
             "1-sigma of the lever arm: > 0 estimates it while the constraint is on, 0: exact [m]")
      .Field("vehicle_sideslip_rad_per_mps2", &IO::vehicle_sideslip_rad_per_mps2,
             "The tyres' slip angle per lateral acceleration [rad/(m/s^2)]")
      .Field("vehicle_sideslip_sigma_rad_per_mps2", &IO::vehicle_sideslip_sigma_rad_per_mps2,
             "1-sigma of the sideslip: > 0 estimates it while the constraint is on, 0: exact "
             "[rad/(m/s^2)]")
      .Field("gnss", &IO::gnss, "GnssPriorOptions (lever arm, floors, gates, outage timeout).")
      .Validated()
      .Done();

  using RP = RangeProjectionOptions;
  OptionsClass<RP>(m, "RangeProjectionOptions", "Spherical range-image geometry (HDL-64E).")
      .Field("rows", &RP::rows, "Elevation bins")
      .Field("cols", &RP::cols, "Azimuth bins")
      .Field("fov_up_deg", &RP::fov_up_deg, "[deg]")
      .Field("fov_down_deg", &RP::fov_down_deg, "[deg]")
      .Field("min_range_m", &RP::min_range_m, "[m]")
      .Field("max_range_m", &RP::max_range_m, "[m]")
      .Field("normal_max_range_jump_m", &RP::normal_max_range_jump_m, "[m]")
      .Field("normal_max_range_jump_ratio", &RP::normal_max_range_jump_ratio, "")
      .Field("normal_col_step", &RP::normal_col_step, "")
      .Validated()
      .Done();

  using RO = SurfelRendererOptions;
  OptionsClass<RO>(m, "SurfelRendererOptions", "Model image size and surfel facing test.")
      .Field("projection", &RO::projection, "RangeProjectionOptions")
      .Field("min_facing_cos", &RO::min_facing_cos, "")
      .Validated()
      .Done();

  using SM = SurfelMapOptions;
  OptionsClass<SM>(m, "SurfelMapOptions", "SuMa-style surfel map parameters.")
      .Field("renderer", &SM::renderer, "SurfelRendererOptions")
      .Field("max_distance_m", &SM::max_distance_m, "[m]")
      .Field("max_angle_deg", &SM::max_angle_deg, "[deg]")
      .Field("radius_factor", &SM::radius_factor, "")
      .Field("min_radius_m", &SM::min_radius_m, "[m]")
      .Field("max_radius_m", &SM::max_radius_m, "[m]")
      .Field("min_radius_cos", &SM::min_radius_cos, "")
      .Field("min_creation_cos", &SM::min_creation_cos, "")
      .Field("p_stable", &SM::p_stable, "")
      .Field("sigma_angle", &SM::sigma_angle, "")
      .Field("sigma_distance", &SM::sigma_distance, "[m]")
      .Field("confidence_threshold", &SM::confidence_threshold, "")
      .Field("unstable_age_frames", &SM::unstable_age_frames, "")
      .Field("max_confidence", &SM::max_confidence, "")
      .Field("max_update_age_frames", &SM::max_update_age_frames, "")
      .Field("max_weight", &SM::max_weight, "")
      .Field("active_radius_m", &SM::active_radius_m, "[m]")
      .Field("index_cell_size_m", &SM::index_cell_size_m, "[m]")
      .Field("integrate_current_submap_only", &SM::integrate_current_submap_only, "")
      .Validated()
      .Done();

  using PI = ProjectiveIcpOptions;
  OptionsClass<PI>(m, "ProjectiveIcpOptions", "Frame-to-model projective ICP (level 1).")
      .Field("max_distance", &PI::max_distance, "[m]")
      .Field("max_angle_deg", &PI::max_angle_deg, "[deg]")
      .Field("huber_delta", &PI::huber_delta, "[m]; <= 0: no robust loss")
      .Field("max_iterations", &PI::max_iterations, "")
      .Field("min_correspondences", &PI::min_correspondences, "")
      .Field("rotation_eps", &PI::rotation_eps, "[rad]")
      .Field("translation_eps", &PI::translation_eps, "[m]")
      .Field("degeneracy_threshold", &PI::degeneracy_threshold, "")
      .Field("freeze_degenerate_directions", &PI::freeze_degenerate_directions, "")
      .Field("pixel_stride", &PI::pixel_stride, "")
      .Validated()
      .Done();

  using PT = PointIcpOptions;
  OptionsClass<PT>(m, "PointIcpOptions", "KD-tree point-to-plane ICP (map-to-map, loops).")
      .Field("max_correspondence_distance", &PT::max_correspondence_distance, "[m]")
      .Field("num_normal_neighbors", &PT::num_normal_neighbors, ">= 3")
      .Field("max_surface_variation", &PT::max_surface_variation, "")
      .Field("huber_delta", &PT::huber_delta, "[m]")
      .Field("max_iterations", &PT::max_iterations, "")
      .Field("min_correspondences", &PT::min_correspondences, "")
      .Field("rotation_eps", &PT::rotation_eps, "[rad]")
      .Field("translation_eps", &PT::translation_eps, "[m]")
      .Field("degeneracy_threshold", &PT::degeneracy_threshold, "")
      .Field("freeze_degenerate_directions", &PT::freeze_degenerate_directions, "")
      .Field("source_voxel_size", &PT::source_voxel_size, "[m]; 0 keeps all")
      .Validated()
      .Done();

  using SW = SlidingWindowOptions;
  OptionsClass<SW>(m, "SlidingWindowOptions", "Level-1 sliding-window graph.")
      .Field("window_size", &SW::window_size, "> 0")
      .Field("exit_mode", &SW::exit_mode, "WindowExitMode")
      .Field("max_iterations", &SW::max_iterations, "")
      .Field("max_solve_time_s", &SW::max_solve_time_s, "[s]")
      .Field("function_tolerance", &SW::function_tolerance, "")
      .Field("consistency_gate_chi2", &SW::consistency_gate_chi2, "6 dof")
      .Field("inconsistency_action", &SW::inconsistency_action, "InconsistencyAction")
      .Field("marginalization_eigen_threshold", &SW::marginalization_eigen_threshold, "")
      .Validated()
      .Done();

  using DS = DeskewOptions;
  OptionsClass<DS>(m, "DeskewOptions", "How level 1 de-skews a scan.")
      .Field("num_knots", &DS::num_knots, "0 = exact per point")
      .Validated()
      .Done();

  using DO = DynamicObjectOptions;
  OptionsClass<DO>(m, "DynamicObjectOptions",
                   "How level 1 keeps moving objects out of registration and the maps.")
      .Field("enabled", &DO::enabled, "")
      .Field("min_object_pixels", &DO::min_object_pixels, "")
      .Field("segmentation_angle_deg", &DO::segmentation_angle_deg, "[deg]")
      .Field("ground_max_tilt_deg", &DO::ground_max_tilt_deg, "[deg]")
      .Field("min_residual_m", &DO::min_residual_m, "[m]")
      .Field("residual_sigmas", &DO::residual_sigmas, "")
      .Field("min_outlier_fraction", &DO::min_outlier_fraction, "")
      .Validated()
      .Done();

  using IP = ImuPreintegration::Options;
  OptionsClass<IP>(m, "ImuPreintegrationOptions", "IMU preintegration noise (F_Prein).")
      .Field("gyro_noise_density", &IP::gyro_noise_density, "[rad/s/sqrt(Hz)]")
      .Field("accel_noise_density", &IP::accel_noise_density, "[m/s^2/sqrt(Hz)]")
      .Field("gyro_bias_random_walk", &IP::gyro_bias_random_walk, "[rad/s^2/sqrt(Hz)]")
      .Field("accel_bias_random_walk", &IP::accel_bias_random_walk, "[m/s^3/sqrt(Hz)]")
      .Field("max_sample_dt_s", &IP::max_sample_dt_s, "[s]")
      .Validated()
      .Done();

  using LO = Level1Options;
  OptionsClass<LO>(m, "LocalizerOptions",
                   "Level1Options: level 1 (the mode, map and threads are MappingSystem's).")
      .Field("submap_duration_s", &LO::submap_duration_s, "WT [s]")
      .Field("surfels", &LO::surfels, "SurfelMapOptions")
      .Field("icp", &LO::icp, "ProjectiveIcpOptions")
      .Field("window", &LO::window, "SlidingWindowOptions")
      .Field("deskew", &LO::deskew, "DeskewOptions")
      .Field("dynamic", &LO::dynamic, "DynamicObjectOptions")
      .Field("imu", &LO::imu, "ImuPreintegrationOptions")
      .Field("renderer", &LO::renderer, "SurfelRendererBackend")
      .Field("model_radius_m", &LO::model_radius_m, "[m]")
      .Field("min_model_confidence", &LO::min_model_confidence, "")
      .Field("previous_submap_model_s", &LO::previous_submap_model_s, "[s]")
      .Field("odom_sigma_rot_rad", &LO::odom_sigma_rot_rad, "[rad]")
      .Field("odom_sigma_trans_m", &LO::odom_sigma_trans_m, "[m]")
      .Field("cv_sigma_rot_rad", &LO::cv_sigma_rot_rad, "[rad]")
      .Field("cv_sigma_trans_m", &LO::cv_sigma_trans_m, "[m]")
      .Field("reg_cov_scale", &LO::reg_cov_scale, "")
      .Field("reg_sigma_floor_rot_rad", &LO::reg_sigma_floor_rot_rad, "[rad]")
      .Field("reg_sigma_floor_trans_m", &LO::reg_sigma_floor_trans_m, "[m]")
      .Field("min_inlier_ratio", &LO::min_inlier_ratio, "")
      .Field("registration_voxel_m", &LO::registration_voxel_m, "[m]")
      .Field("per_submap_surfels", &LO::per_submap_surfels, "")
      .Field("lidar_only_initial_velocity", &LO::lidar_only_initial_velocity,
             "lidar_only starts from the POS's velocity as well as its pose")
      .Field("refine_constant_velocity_deskew", &LO::refine_constant_velocity_deskew,
             "a constant-velocity de-skew is refined from the registration (second pass)")
      .Field("archive_surfels", &LO::archive_surfels, "")
      .Field("spill_dir", &LO::spill_dir, "Finished submaps' clouds go here; '' = memory.")
      .Validated()
      .Done();

  using SO = Level2Options;
  OptionsClass<SO>(m, "Level2Options", "Level2Options: level 2 and loop closure.")
      .Field("enabled", &SO::enabled, "")
      .Field("use_map_to_map", &SO::use_map_to_map, "")
      .Field("use_gnss", &SO::use_gnss, "")
      .Field("use_loops", &SO::use_loops, "")
      .Field("loop_distance_m", &SO::loop_distance_m, "D_thr [m]")
      .Field("loop_min_submap_gap", &SO::loop_min_submap_gap, "")
      .Field("loop_min_inlier_ratio", &SO::loop_min_inlier_ratio, "")
      .Field("loop_max_rms_m", &SO::loop_max_rms_m, "[m]")
      .Field("loop_gate_chi2", &SO::loop_gate_chi2, "")
      .Field("long_outage_s", &SO::long_outage_s, "[s]")
      .Field("reckon_sigma_rot_rad", &SO::reckon_sigma_rot_rad, "[rad]")
      .Field("reckon_sigma_trans_m", &SO::reckon_sigma_trans_m, "[m]")
      .Field("reckon_sigma_rot_rad_per_m", &SO::reckon_sigma_rot_rad_per_m, "[rad/m]")
      .Field("reckon_sigma_trans_per_m", &SO::reckon_sigma_trans_per_m, "[m/m]")
      .Field("reckon_from_level1", &SO::reckon_from_level1, "")
      .Field("gnss_sigma_scale", &SO::gnss_sigma_scale, "")
      .Field("gnss_correlation_s", &SO::gnss_correlation_s, "[s]")
      .Field("pos_attitude_correlation_s", &SO::pos_attitude_correlation_s, "[s]")
      .Field("pos_attitude_cross_covariance", &SO::pos_attitude_cross_covariance, "")
      .Field("gnss_bias_states", &SO::gnss_bias_states,
             "GNSS errors as Gauss-Markov bias nodes instead of gnss_correlation_s")
      .Field("gnss_bias_rtk_fixed", &SO::gnss_bias_rtk_fixed, "GnssErrorModel")
      .Field("gnss_bias_rtk_float", &SO::gnss_bias_rtk_float, "GnssErrorModel")
      .Field("gnss_bias_code", &SO::gnss_bias_code, "GnssErrorModel")
      .Field("gnss_bias_node_interval_s", &SO::gnss_bias_node_interval_s, "[s]")
      .Field("attitude_prior_sigma_rad", &SO::attitude_prior_sigma_rad, "[rad]")
      .Field("max_iterations", &SO::max_iterations, "")
      .Field("icp", &SO::icp, "PointIcpOptions")
      .Validated()
      .Done();

  using IN = ImuNoiseSpec;
  OptionsClass<IN>(m, "ImuNoiseSpec",
                   "An IMU's noise from its datasheet, SI (imu_noise.yaml; "
                   "Options.set_imu_noise).")
      .Field("model", &IN::model, "Free text.")
      .Field("gyro_noise_density", &IN::gyro_noise_density, "Angle random walk [rad/s/sqrt(Hz)].")
      .Field("accel_noise_density", &IN::accel_noise_density,
             "Velocity random walk [m/s^2/sqrt(Hz)].")
      .Field("gyro_bias_instability", &IN::gyro_bias_instability, "[rad/s]")
      .Field("gyro_bias_correlation_time_s", &IN::gyro_bias_correlation_time_s, "[s]")
      .Field("accel_bias_instability", &IN::accel_bias_instability, "[m/s^2]")
      .Field("accel_bias_correlation_time_s", &IN::accel_bias_correlation_time_s, "[s]")
      .Field("gyro_turn_on_bias_sigma", &IN::gyro_turn_on_bias_sigma, "[rad/s]; 0 = not stated.")
      .Field("accel_turn_on_bias_sigma", &IN::accel_turn_on_bias_sigma, "[m/s^2]; 0 = not stated.")
      .Validated()
      .Done();

  using MO = MappingSystem::Options;
  OptionsClass<MO>(m, "Options",
                   "MappingSystem::Options with the C++ defaults. Nested: ins (InsOptions), "
                   "localizer (LocalizerOptions), level2 (Level2Options).")
      .Field("mode", &MO::mode, "MappingMode")
      .Property(
          "T_body_lidar", [](const MO& o) { return IsometryToArray(o.T_body_lidar); },
          [](MO& o, py::object T) { o.T_body_lidar = ArrayToIsometry(T, "T_body_lidar"); },
          "4 x 4 (KITTI: inverse of calib_imu_to_velo).")
      .Field("origin", &MO::origin, "GeodeticPoint or None (= the first valid GNSS fix).")
      .Field("gnss_outages", &MO::gnss_outages,
             "List of (start_s, duration_s) relative to the first scan; assign a new list.")
      .Field("ins", &MO::ins, "InsOptions")
      .Field("localizer", &MO::localizer, "LocalizerOptions")
      .Field("level2", &MO::level2, "Level2Options")
      .Field("map_max_range_m", &MO::map_max_range_m, "[m]")
      .Field("map_voxel_m", &MO::map_voxel_m, "[m]")
      .Field("max_pos_jump_m", &MO::max_pos_jump_m, "[m]")
      .Field("max_pos_jump_rad", &MO::max_pos_jump_rad, "[rad]")
      .Field("num_threads", &MO::num_threads, "The one thread count, in [1, 64].")
      .Field("use_stated_imu_noise", &MO::use_stated_imu_noise,
             "Model the IMU with the noise its input states (run_drive; DriveStreams.imu_noise).")
      .Field("vehicle_nhc_sigma_mps", &MO::vehicle_nhc_sigma_mps,
             "Non-holonomic constraint sigma [m/s] run_drive sets as ins.nhc_sigma_mps where the "
             "input's IMU frame is the vehicle's (DriveStreams.imu_frame_is_vehicle_frame) and "
             "ins.nhc_sigma_mps is 0; 0: never.")
      .Validated()
      .Done()
      .def(
          "set_imu_noise",
          [](MO& o, const ImuNoiseSpec& spec) {
            ThrowIfError(spec.Validate());
            o.SetImuNoise(spec);
          },
          py::arg("spec"),
          "The IMU's datasheet noise in ins and localizer.imu (what run_drive does with "
          "DriveStreams.imu_noise).");
}

}  // namespace slam_mms::python
