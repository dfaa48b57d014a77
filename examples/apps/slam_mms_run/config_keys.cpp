#include "slam_mms_run/config_keys.hpp"

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

namespace slam_mms::app::config {
namespace {

bool ToDouble(const std::string& text, double* v) {
  if (text.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  if (errno != 0 || end != text.c_str() + text.size() || !std::isfinite(x)) return false;
  *v = x;
  return true;
}

bool ToInt(const std::string& text, int* v) {
  if (text.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const long x = std::strtol(text.c_str(), &end, 10);
  if (errno != 0 || end != text.c_str() + text.size() || x < -2147483647L || x > 2147483647L) {
    return false;
  }
  *v = static_cast<int>(x);
  return true;
}

bool ToBool(std::string text, bool* v) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  static const std::map<std::string, bool> kWords = {
      {"true", true}, {"false", false}, {"1", true},  {"0", false},
      {"yes", true},  {"no", false},    {"on", true}, {"off", false}};
  const auto it = kWords.find(text);
  if (it == kWords.end()) return false;
  *v = it->second;
  return true;
}

// [x, y, z] (a YAML sequence of three numbers) or "x y z" / "x, y, z" in one scalar.
bool ToVector3(const YAML::Node& node, Eigen::Vector3d* v) {
  std::vector<std::string> parts;
  if (node.IsSequence()) {
    for (const YAML::Node& e : node) {
      if (!e.IsScalar()) return false;
      parts.push_back(e.Scalar());
    }
  } else if (node.IsScalar()) {
    std::string t = node.Scalar();
    for (char& c : t) {
      if (c == ',') c = ' ';
    }
    std::istringstream in(t);
    std::string p;
    while (in >> p) parts.push_back(p);
  }
  if (parts.size() != 3) return false;
  Eigen::Vector3d x;
  for (int k = 0; k < 3; ++k) {
    if (!ToDouble(parts[k], &x(k))) return false;
  }
  *v = x;
  return true;
}

// The shortest text that reads back to the same double (float: to the same float).
template <typename T>
std::string ShortestText(T v) {
  char buf[64];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}
std::string FormatDouble(double v) { return ShortestText(v); }
std::string FormatFloat(float v) { return ShortestText(v); }

// A YAML double-quoted string.
std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\x%02x", static_cast<unsigned char>(c));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

template <typename T>
T& Field(const std::function<T*(Options*)>& field, const Options& o) {
  return *field(const_cast<Options*>(&o));
}

KeyHandler Double(std::function<double*(Options*)> field) {
  KeyHandler h;
  h.type = "double";
  h.set = [field](const YAML::Node& v, Options* o) { return ToDouble(v.Scalar(), field(o)); };
  h.yaml = [field](const Options& o) { return FormatDouble(Field(field, o)); };
  h.json = [field](const Options& o) { return Json(Field(field, o)); };
  return h;
}
KeyHandler Float(std::function<float*(Options*)> field) {
  KeyHandler h;
  h.type = "double";
  h.set = [field](const YAML::Node& v, Options* o) {
    double x = 0.0;
    if (!ToDouble(v.Scalar(), &x)) return false;
    *field(o) = static_cast<float>(x);
    return true;
  };
  h.yaml = [field](const Options& o) { return FormatFloat(Field(field, o)); };
  // Through the shortest text, so that JSON shows 0.3 rather than 0.30000001192092896.
  h.json = [field](const Options& o) {
    return Json(std::strtod(FormatFloat(Field(field, o)).c_str(), nullptr));
  };
  return h;
}
KeyHandler Int(std::function<int*(Options*)> field) {
  KeyHandler h;
  h.type = "int";
  h.set = [field](const YAML::Node& v, Options* o) { return ToInt(v.Scalar(), field(o)); };
  h.yaml = [field](const Options& o) { return std::to_string(Field(field, o)); };
  h.json = [field](const Options& o) { return Json(Field(field, o)); };
  return h;
}
KeyHandler Bool(std::function<bool*(Options*)> field) {
  KeyHandler h;
  h.type = "bool";
  h.set = [field](const YAML::Node& v, Options* o) { return ToBool(v.Scalar(), field(o)); };
  h.yaml = [field](const Options& o) { return std::string(Field(field, o) ? "true" : "false"); };
  h.json = [field](const Options& o) { return Json(Field(field, o)); };
  return h;
}
KeyHandler Vector3(std::function<Eigen::Vector3d*(Options*)> field) {
  KeyHandler h;
  h.type = "vector3";
  h.sequence = true;
  h.set = [field](const YAML::Node& v, Options* o) { return ToVector3(v, field(o)); };
  h.yaml = [field](const Options& o) {
    const Eigen::Vector3d& x = Field(field, o);
    return "[" + FormatDouble(x.x()) + ", " + FormatDouble(x.y()) + ", " + FormatDouble(x.z()) +
           "]";
  };
  h.json = [field](const Options& o) {
    const Eigen::Vector3d& x = Field(field, o);
    return Json::array({x.x(), x.y(), x.z()});
  };
  return h;
}
template <typename E>
KeyHandler Enum(std::function<E*(Options*)> field, std::vector<std::pair<std::string, E>> names) {
  KeyHandler h;
  h.type = "enum:";
  for (size_t i = 0; i < names.size(); ++i) h.type += (i ? "|" : " ") + names[i].first;
  auto name_of = [field, names](const Options& o) {
    for (const auto& [name, value] : names) {
      if (Field(field, o) == value) return name;
    }
    return std::string("?");
  };
  h.set = [field, names](const YAML::Node& v, Options* o) {
    for (const auto& [name, value] : names) {
      if (name == v.Scalar()) {
        *field(o) = value;
        return true;
      }
    }
    return false;
  };
  h.yaml = name_of;
  h.json = [name_of](const Options& o) { return Json(name_of(o)); };
  return h;
}
// A folder; ~ or "none" = empty (the option's "not used").
KeyHandler Path(std::function<std::filesystem::path*(Options*)> field) {
  KeyHandler h;
  h.type = "path";
  h.nullable = true;
  h.set = [field](const YAML::Node& v, Options* o) {
    if (v.IsNull() || v.Scalar() == "none") {
      *field(o) = std::filesystem::path();
    } else {
      *field(o) = std::filesystem::path(v.Scalar());
    }
    return true;
  };
  h.yaml = [field](const Options& o) {
    const std::filesystem::path& p = Field(field, o);
    return p.empty() ? std::string("~") : Quote(p.string());
  };
  h.json = [field](const Options& o) {
    const std::filesystem::path& p = Field(field, o);
    return p.empty() ? Json(nullptr) : Json(p.string());
  };
  return h;
}
// The origin is optional in the options: the three keys together set it, ~ for all three unsets it
// (ApplyConfigText checks that they come together).
KeyHandler OriginField(double GeodeticPoint::*member) {
  KeyHandler h;
  h.type = "double";
  h.nullable = true;
  h.set = [member](const YAML::Node& v, Options* o) {
    if (v.IsNull()) return true;
    double x = 0.0;
    if (!ToDouble(v.Scalar(), &x)) return false;
    if (!o->system.origin) o->system.origin = GeodeticPoint();
    (*o->system.origin).*member = x;
    return true;
  };
  h.yaml = [member](const Options& o) {
    return o.system.origin ? FormatDouble((*o.system.origin).*member) : std::string("~");
  };
  h.json = [member](const Options& o) {
    return o.system.origin ? Json((*o.system.origin).*member) : Json(nullptr);
  };
  return h;
}

const std::vector<std::pair<std::string, GnssFixType>>& FixTypeNames() {
  static const std::vector<std::pair<std::string, GnssFixType>> kNames = {
      {"none", GnssFixType::kNone},
      {"single", GnssFixType::kSingle},
      {"differential", GnssFixType::kDifferential},
      {"rtk_float", GnssFixType::kRtkFloat},
      {"rtk_fixed", GnssFixType::kRtkFixed}};
  return kNames;
}

// The key table, in documentation order.
}  // namespace

const std::vector<std::pair<std::string, KeyHandler>>& Handlers() {
  static const std::vector<std::pair<std::string, KeyHandler>> kHandlers = [] {
    std::vector<std::pair<std::string, KeyHandler>> h;
#define SLAM_MMS_KEY_D(key, expr) h.emplace_back(key, Double([](Options* o) { return &(expr); }))
#define SLAM_MMS_KEY_F(key, expr) h.emplace_back(key, Float([](Options* o) { return &(expr); }))
#define SLAM_MMS_KEY_I(key, expr) h.emplace_back(key, Int([](Options* o) { return &(expr); }))
#define SLAM_MMS_KEY_B(key, expr) h.emplace_back(key, Bool([](Options* o) { return &(expr); }))
// A GnssErrorModel's two keys under `prefix` (the POS filter's and level 2's).
#define SLAM_MMS_KEYS_GNSS_ERROR(prefix, expr)                               \
  SLAM_MMS_KEY_D(prefix ".correlated_fraction", (expr).correlated_fraction); \
  SLAM_MMS_KEY_D(prefix ".correlation_time_s", (expr).correlation_time_s)
    // MappingSystem.
    h.emplace_back("origin_latitude_deg", OriginField(&GeodeticPoint::latitude_deg));
    h.emplace_back("origin_longitude_deg", OriginField(&GeodeticPoint::longitude_deg));
    h.emplace_back("origin_height_m", OriginField(&GeodeticPoint::height_m));
    SLAM_MMS_KEY_D("map_max_range_m", o->system.map_max_range_m);
    SLAM_MMS_KEY_D("map_voxel_m", o->system.map_voxel_m);
    SLAM_MMS_KEY_D("max_pos_jump_m", o->system.max_pos_jump_m);
    SLAM_MMS_KEY_D("max_pos_jump_rad", o->system.max_pos_jump_rad);
    SLAM_MMS_KEY_I("num_threads", o->system.num_threads);
    SLAM_MMS_KEY_B("use_stated_imu_noise", o->system.use_stated_imu_noise);
    SLAM_MMS_KEY_D("vehicle_nhc_sigma_mps", o->system.vehicle_nhc_sigma_mps);
    // POS (InsFilter).
    SLAM_MMS_KEY_D("ins.gyro_noise_density", o->system.ins.gyro_noise_density);
    SLAM_MMS_KEY_D("ins.accel_noise_density", o->system.ins.accel_noise_density);
    SLAM_MMS_KEY_D("ins.gyro_bias_random_walk", o->system.ins.gyro_bias_random_walk);
    SLAM_MMS_KEY_D("ins.accel_bias_random_walk", o->system.ins.accel_bias_random_walk);
    SLAM_MMS_KEY_D("ins.gravity_mps2", o->system.ins.gravity_mps2);
    SLAM_MMS_KEY_D("ins.init_sigma_position_m", o->system.ins.init_sigma_position_m);
    SLAM_MMS_KEY_D("ins.init_sigma_velocity_mps", o->system.ins.init_sigma_velocity_mps);
    SLAM_MMS_KEY_D("ins.init_sigma_roll_pitch_rad", o->system.ins.init_sigma_roll_pitch_rad);
    SLAM_MMS_KEY_D("ins.init_sigma_yaw_rad", o->system.ins.init_sigma_yaw_rad);
    SLAM_MMS_KEY_D("ins.init_sigma_accel_bias_mps2", o->system.ins.init_sigma_accel_bias_mps2);
    SLAM_MMS_KEY_D("ins.init_sigma_gyro_bias_radps", o->system.ins.init_sigma_gyro_bias_radps);
    SLAM_MMS_KEY_B("ins.use_stated_attitude_sigma", o->system.ins.use_stated_attitude_sigma);
    SLAM_MMS_KEY_D("ins.max_imu_gap_s", o->system.ins.max_imu_gap_s);
    SLAM_MMS_KEY_D("ins.max_fix_latency_s", o->system.ins.max_fix_latency_s);
    SLAM_MMS_KEY_D("ins.max_extrapolation_s", o->system.ins.max_extrapolation_s);
    SLAM_MMS_KEY_D("ins.history_s", o->system.ins.history_s);
    SLAM_MMS_KEYS_GNSS_ERROR("ins.gnss_error_rtk_fixed", o->system.ins.gnss_error_rtk_fixed);
    SLAM_MMS_KEYS_GNSS_ERROR("ins.gnss_error_rtk_float", o->system.ins.gnss_error_rtk_float);
    SLAM_MMS_KEYS_GNSS_ERROR("ins.gnss_error_code", o->system.ins.gnss_error_code);
    SLAM_MMS_KEY_B("ins.zupt", o->system.ins.zupt);
    SLAM_MMS_KEY_D("ins.zupt_window_s", o->system.ins.zupt_window_s);
    SLAM_MMS_KEY_D("ins.zupt_max_gyro_radps", o->system.ins.zupt_max_gyro_radps);
    SLAM_MMS_KEY_D("ins.zupt_max_accel_mps2", o->system.ins.zupt_max_accel_mps2);
    SLAM_MMS_KEY_D("ins.zupt_max_speed_mps", o->system.ins.zupt_max_speed_mps);
    SLAM_MMS_KEY_D("ins.zupt_sigma_mps", o->system.ins.zupt_sigma_mps);
    SLAM_MMS_KEY_D("ins.zupt_interval_s", o->system.ins.zupt_interval_s);
    SLAM_MMS_KEY_D("ins.nhc_sigma_mps", o->system.ins.nhc_sigma_mps);
    SLAM_MMS_KEY_D("ins.nhc_min_speed_mps", o->system.ins.nhc_min_speed_mps);
    SLAM_MMS_KEY_D("ins.nhc_lateral_correlation_time_s",
                   o->system.ins.nhc_lateral_correlation_time_s);
    SLAM_MMS_KEY_D("ins.nhc_vertical_correlation_time_s",
                   o->system.ins.nhc_vertical_correlation_time_s);
    SLAM_MMS_KEY_D("ins.vehicle_pitch_misalignment_rad",
                   o->system.ins.vehicle_pitch_misalignment_rad);
    SLAM_MMS_KEY_D("ins.vehicle_yaw_misalignment_rad", o->system.ins.vehicle_yaw_misalignment_rad);
    SLAM_MMS_KEY_D("ins.vehicle_misalignment_sigma_rad",
                   o->system.ins.vehicle_misalignment_sigma_rad);
    SLAM_MMS_KEY_D("ins.vehicle_lever_arm_m", o->system.ins.vehicle_lever_arm_m);
    SLAM_MMS_KEY_D("ins.vehicle_lever_arm_sigma_m", o->system.ins.vehicle_lever_arm_sigma_m);
    SLAM_MMS_KEY_D("ins.vehicle_sideslip_rad_per_mps2",
                   o->system.ins.vehicle_sideslip_rad_per_mps2);
    SLAM_MMS_KEY_D("ins.vehicle_sideslip_sigma_rad_per_mps2",
                   o->system.ins.vehicle_sideslip_sigma_rad_per_mps2);
    // GNSS (GnssPrior).
    h.emplace_back("ins.gnss.t_body_antenna",
                   Vector3([](Options* o) { return &o->system.ins.gnss.t_body_antenna; }));
    SLAM_MMS_KEY_D("ins.gnss.sigma_floor_horizontal_m",
                   o->system.ins.gnss.sigma_floor_horizontal_m);
    SLAM_MMS_KEY_D("ins.gnss.sigma_floor_vertical_m", o->system.ins.gnss.sigma_floor_vertical_m);
    SLAM_MMS_KEY_D("ins.gnss.max_sigma_horizontal_m", o->system.ins.gnss.max_sigma_horizontal_m);
    h.emplace_back("ins.gnss.min_fix_type",
                   Enum<GnssFixType>([](Options* o) { return &o->system.ins.gnss.min_fix_type; },
                                     FixTypeNames()));
    h.emplace_back(
        "ins.gnss.full_weight_fix_type",
        Enum<GnssFixType>([](Options* o) { return &o->system.ins.gnss.full_weight_fix_type; },
                          FixTypeNames()));
    SLAM_MMS_KEY_D("ins.gnss.downweight_variance_factor",
                   o->system.ins.gnss.downweight_variance_factor);
    SLAM_MMS_KEY_D("ins.gnss.innovation_downweight_chi2",
                   o->system.ins.gnss.innovation_downweight_chi2);
    SLAM_MMS_KEY_D("ins.gnss.innovation_reject_chi2", o->system.ins.gnss.innovation_reject_chi2);
    SLAM_MMS_KEY_D("ins.gnss.max_rejection_streak_s", o->system.ins.gnss.max_rejection_streak_s);
    SLAM_MMS_KEY_D("ins.gnss.max_speed_mps", o->system.ins.gnss.max_speed_mps);
    SLAM_MMS_KEY_D("ins.gnss.outage_timeout_s", o->system.ins.gnss.outage_timeout_s);
    // Level 1 (Localizer).
    SLAM_MMS_KEY_D("localizer.submap_duration_s", o->system.localizer.submap_duration_s);
    SLAM_MMS_KEY_D("localizer.model_radius_m", o->system.localizer.model_radius_m);
    SLAM_MMS_KEY_F("localizer.min_model_confidence", o->system.localizer.min_model_confidence);
    SLAM_MMS_KEY_D("localizer.previous_submap_model_s",
                   o->system.localizer.previous_submap_model_s);
    SLAM_MMS_KEY_D("localizer.odom_sigma_rot_rad", o->system.localizer.odom_sigma_rot_rad);
    SLAM_MMS_KEY_D("localizer.odom_sigma_trans_m", o->system.localizer.odom_sigma_trans_m);
    SLAM_MMS_KEY_D("localizer.cv_sigma_rot_rad", o->system.localizer.cv_sigma_rot_rad);
    SLAM_MMS_KEY_D("localizer.cv_sigma_trans_m", o->system.localizer.cv_sigma_trans_m);
    SLAM_MMS_KEY_D("localizer.reg_cov_scale", o->system.localizer.reg_cov_scale);
    SLAM_MMS_KEY_D("localizer.reg_sigma_floor_rot_rad",
                   o->system.localizer.reg_sigma_floor_rot_rad);
    SLAM_MMS_KEY_D("localizer.reg_sigma_floor_trans_m",
                   o->system.localizer.reg_sigma_floor_trans_m);
    SLAM_MMS_KEY_D("localizer.min_inlier_ratio", o->system.localizer.min_inlier_ratio);
    SLAM_MMS_KEY_D("localizer.registration_voxel_m", o->system.localizer.registration_voxel_m);
    SLAM_MMS_KEY_B("localizer.per_submap_surfels", o->system.localizer.per_submap_surfels);
    SLAM_MMS_KEY_B("localizer.lidar_only_initial_velocity",
                   o->system.localizer.lidar_only_initial_velocity);
    SLAM_MMS_KEY_B("localizer.refine_constant_velocity_deskew",
                   o->system.localizer.refine_constant_velocity_deskew);
    SLAM_MMS_KEY_B("localizer.archive_surfels", o->system.localizer.archive_surfels);
    h.emplace_back("localizer.spill_dir",
                   Path([](Options* o) { return &o->system.localizer.spill_dir; }));
    SLAM_MMS_KEY_I("localizer.surfels.renderer.projection.cols",
                   o->system.localizer.surfels.renderer.projection.cols);
    h.emplace_back(
        "localizer.renderer",
        Enum<SurfelRendererBackend>([](Options* o) { return &o->system.localizer.renderer; },
                                    {{"auto", SurfelRendererBackend::kAuto},
                                     {"cpu", SurfelRendererBackend::kCpu},
                                     {"egl", SurfelRendererBackend::kEgl}}));
    SLAM_MMS_KEY_D("localizer.icp.max_distance", o->system.localizer.icp.max_distance);
    SLAM_MMS_KEY_D("localizer.icp.max_angle_deg", o->system.localizer.icp.max_angle_deg);
    SLAM_MMS_KEY_D("localizer.icp.huber_delta", o->system.localizer.icp.huber_delta);
    SLAM_MMS_KEY_I("localizer.icp.max_iterations", o->system.localizer.icp.max_iterations);
    SLAM_MMS_KEY_I("localizer.icp.min_correspondences",
                   o->system.localizer.icp.min_correspondences);
    SLAM_MMS_KEY_I("localizer.icp.pixel_stride", o->system.localizer.icp.pixel_stride);
    SLAM_MMS_KEY_B("localizer.dynamic.enabled", o->system.localizer.dynamic.enabled);
    SLAM_MMS_KEY_I("localizer.dynamic.min_object_pixels",
                   o->system.localizer.dynamic.min_object_pixels);
    SLAM_MMS_KEY_D("localizer.dynamic.segmentation_angle_deg",
                   o->system.localizer.dynamic.segmentation_angle_deg);
    SLAM_MMS_KEY_D("localizer.dynamic.ground_max_tilt_deg",
                   o->system.localizer.dynamic.ground_max_tilt_deg);
    SLAM_MMS_KEY_D("localizer.dynamic.min_residual_m", o->system.localizer.dynamic.min_residual_m);
    SLAM_MMS_KEY_D("localizer.dynamic.residual_sigmas",
                   o->system.localizer.dynamic.residual_sigmas);
    SLAM_MMS_KEY_D("localizer.dynamic.min_outlier_fraction",
                   o->system.localizer.dynamic.min_outlier_fraction);
    SLAM_MMS_KEY_D("localizer.surfels.max_distance_m", o->system.localizer.surfels.max_distance_m);
    SLAM_MMS_KEY_D("localizer.surfels.active_radius_m",
                   o->system.localizer.surfels.active_radius_m);
    SLAM_MMS_KEY_I("localizer.window.window_size", o->system.localizer.window.window_size);
    SLAM_MMS_KEY_I("localizer.window.max_iterations", o->system.localizer.window.max_iterations);
    SLAM_MMS_KEY_D("localizer.window.max_solve_time_s",
                   o->system.localizer.window.max_solve_time_s);
    SLAM_MMS_KEY_D("localizer.window.consistency_gate_chi2",
                   o->system.localizer.window.consistency_gate_chi2);
    // Level 2 (SubmapManager).
    SLAM_MMS_KEY_B("level2.enabled", o->system.level2.enabled);
    SLAM_MMS_KEY_B("level2.use_map_to_map", o->system.level2.use_map_to_map);
    SLAM_MMS_KEY_B("level2.use_gnss", o->system.level2.use_gnss);
    SLAM_MMS_KEY_B("level2.use_loops", o->system.level2.use_loops);
    SLAM_MMS_KEY_D("level2.loop_distance_m", o->system.level2.loop_distance_m);
    SLAM_MMS_KEY_I("level2.loop_min_submap_gap", o->system.level2.loop_min_submap_gap);
    SLAM_MMS_KEY_D("level2.loop_min_inlier_ratio", o->system.level2.loop_min_inlier_ratio);
    SLAM_MMS_KEY_D("level2.loop_max_rms_m", o->system.level2.loop_max_rms_m);
    SLAM_MMS_KEY_D("level2.loop_gate_chi2", o->system.level2.loop_gate_chi2);
    SLAM_MMS_KEY_D("level2.long_outage_s", o->system.level2.long_outage_s);
    SLAM_MMS_KEY_D("level2.reckon_sigma_rot_rad", o->system.level2.reckon_sigma_rot_rad);
    SLAM_MMS_KEY_D("level2.reckon_sigma_trans_m", o->system.level2.reckon_sigma_trans_m);
    SLAM_MMS_KEY_D("level2.reckon_sigma_rot_rad_per_m",
                   o->system.level2.reckon_sigma_rot_rad_per_m);
    SLAM_MMS_KEY_D("level2.reckon_sigma_trans_per_m", o->system.level2.reckon_sigma_trans_per_m);
    SLAM_MMS_KEY_B("level2.reckon_from_level1", o->system.level2.reckon_from_level1);
    SLAM_MMS_KEY_D("level2.gnss_sigma_scale", o->system.level2.gnss_sigma_scale);
    SLAM_MMS_KEY_D("level2.gnss_correlation_s", o->system.level2.gnss_correlation_s);
    SLAM_MMS_KEY_D("level2.pos_attitude_correlation_s",
                   o->system.level2.pos_attitude_correlation_s);
    SLAM_MMS_KEY_B("level2.pos_attitude_cross_covariance",
                   o->system.level2.pos_attitude_cross_covariance);
    SLAM_MMS_KEY_B("level2.gnss_bias_states", o->system.level2.gnss_bias_states);
    SLAM_MMS_KEYS_GNSS_ERROR("level2.gnss_bias_rtk_fixed", o->system.level2.gnss_bias_rtk_fixed);
    SLAM_MMS_KEYS_GNSS_ERROR("level2.gnss_bias_rtk_float", o->system.level2.gnss_bias_rtk_float);
    SLAM_MMS_KEYS_GNSS_ERROR("level2.gnss_bias_code", o->system.level2.gnss_bias_code);
    SLAM_MMS_KEY_D("level2.gnss_bias_node_interval_s", o->system.level2.gnss_bias_node_interval_s);
    SLAM_MMS_KEY_D("level2.attitude_prior_sigma_rad", o->system.level2.attitude_prior_sigma_rad);
    SLAM_MMS_KEY_I("level2.max_iterations", o->system.level2.max_iterations);
    // The drive runner (RunDrive's passes over the whole drive; DriveRunOptions).
    SLAM_MMS_KEY_B("drive.estimate_extrinsics", o->drive.estimate_extrinsics);
    h.emplace_back(
        "drive.extrinsic_calibration.attitude_reference",
        Enum<ExtrinsicCalibrationOptions::AttitudeReference>(
            [](Options* o) { return &o->drive.extrinsic_calibration.attitude_reference; },
            {{"pos", ExtrinsicCalibrationOptions::AttitudeReference::kPos},
             {"travel_direction",
              ExtrinsicCalibrationOptions::AttitudeReference::kTravelDirection}}));
    SLAM_MMS_KEY_I("drive.extrinsic_calibration.max_scans",
                   o->drive.extrinsic_calibration.max_scans);
    SLAM_MMS_KEY_D("drive.extrinsic_calibration.max_pos_sigma_m",
                   o->drive.extrinsic_calibration.max_pos_sigma_m);
    SLAM_MMS_KEY_D("drive.extrinsic_calibration.max_pos_sigma_ratio",
                   o->drive.extrinsic_calibration.max_pos_sigma_ratio);
    SLAM_MMS_KEY_B("drive.extrinsic_calibration.estimate_rotation",
                   o->drive.extrinsic_calibration.estimate_rotation);
    SLAM_MMS_KEY_B("drive.extrinsic_calibration.estimate_translation",
                   o->drive.extrinsic_calibration.estimate_translation);
    SLAM_MMS_KEY_B("drive.extrinsic_calibration.estimate_time_offset",
                   o->drive.extrinsic_calibration.estimate_time_offset);
    SLAM_MMS_KEY_B("drive.extrinsic_calibration.estimate_pos_drift",
                   o->drive.extrinsic_calibration.estimate_pos_drift);
    SLAM_MMS_KEY_D("drive.extrinsic_calibration.pos_drift_knot_interval_s",
                   o->drive.extrinsic_calibration.pos_drift_knot_interval_s);
    SLAM_MMS_KEY_D("drive.extrinsic_calibration.pos_error_correlation_s",
                   o->drive.extrinsic_calibration.pos_error_correlation_s);
    SLAM_MMS_KEY_D("drive.extrinsic_calibration.pos_max_velocity_error_mps",
                   o->drive.extrinsic_calibration.pos_max_velocity_error_mps);
    SLAM_MMS_KEY_D("drive.extrinsic_calibration.max_sigma_rpy_rad",
                   o->drive.extrinsic_calibration.max_sigma_rpy_rad);
    SLAM_MMS_KEY_D("drive.extrinsic_calibration.min_significance",
                   o->drive.extrinsic_calibration.min_significance);
    SLAM_MMS_KEY_D("drive.extrinsic_calibration.systematic_error_m",
                   o->drive.extrinsic_calibration.systematic_error_m);
#undef SLAM_MMS_KEY_D
#undef SLAM_MMS_KEY_F
#undef SLAM_MMS_KEY_I
#undef SLAM_MMS_KEY_B
#undef SLAM_MMS_KEYS_GNSS_ERROR
    return h;
  }();
  return kHandlers;
}

}  // namespace slam_mms::app::config
