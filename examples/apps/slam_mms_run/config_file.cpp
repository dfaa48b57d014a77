#include "slam_mms_run/config_file.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

namespace slam_mms::app {
namespace {

using Options = MappingSystem::Options;

// One accepted key: how to parse a value into the options and how to print the current value.
struct KeyHandler {
  std::string type;
  std::function<bool(const std::string& value, Options* o)> set;
  std::function<std::string(const Options& o)> get;
};

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

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

bool ToBool(const std::string& text, bool* v) {
  static const std::map<std::string, bool> kWords = {
      {"true", true}, {"false", false}, {"1", true},  {"0", false},
      {"yes", true},  {"no", false},    {"on", true}, {"off", false}};
  const auto it = kWords.find(text);
  if (it == kWords.end()) return false;
  *v = it->second;
  return true;
}

bool ToVector3(const std::string& text, Eigen::Vector3d* v) {
  std::string t = text;
  for (char& c : t) {
    if (c == ',') c = ' ';
  }
  std::istringstream in(t);
  std::string a, b, c, extra;
  if (!(in >> a >> b >> c) || (in >> extra)) return false;
  Eigen::Vector3d x;
  if (!ToDouble(a, &x.x()) || !ToDouble(b, &x.y()) || !ToDouble(c, &x.z())) return false;
  *v = x;
  return true;
}

std::string FormatDouble(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

KeyHandler Double(std::function<double*(Options*)> field) {
  return {"double", [field](const std::string& v, Options* o) { return ToDouble(v, field(o)); },
          [field](const Options& o) { return FormatDouble(*field(const_cast<Options*>(&o))); }};
}
KeyHandler Float(std::function<float*(Options*)> field) {
  return {"double",
          [field](const std::string& v, Options* o) {
            double x = 0.0;
            if (!ToDouble(v, &x)) return false;
            *field(o) = static_cast<float>(x);
            return true;
          },
          [field](const Options& o) { return FormatDouble(*field(const_cast<Options*>(&o))); }};
}
KeyHandler Int(std::function<int*(Options*)> field) {
  return {"int", [field](const std::string& v, Options* o) { return ToInt(v, field(o)); },
          [field](const Options& o) { return std::to_string(*field(const_cast<Options*>(&o))); }};
}
KeyHandler Bool(std::function<bool*(Options*)> field) {
  return {"bool", [field](const std::string& v, Options* o) { return ToBool(v, field(o)); },
          [field](const Options& o) {
            return std::string(*field(const_cast<Options*>(&o)) ? "true" : "false");
          }};
}
KeyHandler Vector3(std::function<Eigen::Vector3d*(Options*)> field) {
  return {"vector3", [field](const std::string& v, Options* o) { return ToVector3(v, field(o)); },
          [field](const Options& o) {
            const Eigen::Vector3d& x = *field(const_cast<Options*>(&o));
            return FormatDouble(x.x()) + " " + FormatDouble(x.y()) + " " + FormatDouble(x.z());
          }};
}
template <typename E>
KeyHandler Enum(std::function<E*(Options*)> field, std::vector<std::pair<std::string, E>> names) {
  std::string type = "enum:";
  for (size_t i = 0; i < names.size(); ++i) type += (i ? "|" : " ") + names[i].first;
  return {type,
          [field, names](const std::string& v, Options* o) {
            for (const auto& [name, value] : names) {
              if (name == v) {
                *field(o) = value;
                return true;
              }
            }
            return false;
          },
          [field, names](const Options& o) {
            for (const auto& [name, value] : names) {
              if (*field(const_cast<Options*>(&o)) == value) return name;
            }
            return std::string("?");
          }};
}
// A folder; "none" = empty (the option's "not used").
KeyHandler Path(std::function<std::filesystem::path*(Options*)> field) {
  return {"path",
          [field](const std::string& v, Options* o) {
            *field(o) = v == "none" ? std::filesystem::path() : std::filesystem::path(v);
            return true;
          },
          [field](const Options& o) {
            const std::filesystem::path& p = *field(const_cast<Options*>(&o));
            return p.empty() ? std::string("none") : p.string();
          }};
}
// The origin is optional in the options: the three keys together set it.
KeyHandler OriginField(double GeodeticPoint::*member) {
  return {"double",
          [member](const std::string& v, Options* o) {
            double x = 0.0;
            if (!ToDouble(v, &x)) return false;
            if (!o->origin) o->origin = GeodeticPoint();
            (*o->origin).*member = x;
            return true;
          },
          [](const Options& o) { return std::string("(unset: the first valid GNSS fix)"); }};
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
const std::vector<std::pair<std::string, KeyHandler>>& Handlers() {
  static const std::vector<std::pair<std::string, KeyHandler>> kHandlers = [] {
    std::vector<std::pair<std::string, KeyHandler>> h;
#define SLAM_MMS_KEY_D(key, expr) h.emplace_back(key, Double([](Options* o) { return &(expr); }))
#define SLAM_MMS_KEY_F(key, expr) h.emplace_back(key, Float([](Options* o) { return &(expr); }))
#define SLAM_MMS_KEY_I(key, expr) h.emplace_back(key, Int([](Options* o) { return &(expr); }))
#define SLAM_MMS_KEY_B(key, expr) h.emplace_back(key, Bool([](Options* o) { return &(expr); }))
    // MappingSystem.
    h.emplace_back("origin_latitude_deg", OriginField(&GeodeticPoint::latitude_deg));
    h.emplace_back("origin_longitude_deg", OriginField(&GeodeticPoint::longitude_deg));
    h.emplace_back("origin_height_m", OriginField(&GeodeticPoint::height_m));
    SLAM_MMS_KEY_D("map_max_range_m", o->map_max_range_m);
    SLAM_MMS_KEY_D("map_voxel_m", o->map_voxel_m);
    SLAM_MMS_KEY_D("max_pos_jump_m", o->max_pos_jump_m);
    SLAM_MMS_KEY_D("max_pos_jump_rad", o->max_pos_jump_rad);
    SLAM_MMS_KEY_I("num_threads", o->num_threads);
    // POS (InsFilter).
    SLAM_MMS_KEY_D("ins.gyro_noise_density", o->ins.gyro_noise_density);
    SLAM_MMS_KEY_D("ins.accel_noise_density", o->ins.accel_noise_density);
    SLAM_MMS_KEY_D("ins.gyro_bias_random_walk", o->ins.gyro_bias_random_walk);
    SLAM_MMS_KEY_D("ins.accel_bias_random_walk", o->ins.accel_bias_random_walk);
    SLAM_MMS_KEY_D("ins.gravity_mps2", o->ins.gravity_mps2);
    SLAM_MMS_KEY_D("ins.init_sigma_position_m", o->ins.init_sigma_position_m);
    SLAM_MMS_KEY_D("ins.init_sigma_velocity_mps", o->ins.init_sigma_velocity_mps);
    SLAM_MMS_KEY_D("ins.init_sigma_roll_pitch_rad", o->ins.init_sigma_roll_pitch_rad);
    SLAM_MMS_KEY_D("ins.init_sigma_yaw_rad", o->ins.init_sigma_yaw_rad);
    SLAM_MMS_KEY_D("ins.init_sigma_accel_bias_mps2", o->ins.init_sigma_accel_bias_mps2);
    SLAM_MMS_KEY_D("ins.init_sigma_gyro_bias_radps", o->ins.init_sigma_gyro_bias_radps);
    SLAM_MMS_KEY_D("ins.max_imu_gap_s", o->ins.max_imu_gap_s);
    SLAM_MMS_KEY_D("ins.max_fix_latency_s", o->ins.max_fix_latency_s);
    SLAM_MMS_KEY_D("ins.max_extrapolation_s", o->ins.max_extrapolation_s);
    SLAM_MMS_KEY_D("ins.history_s", o->ins.history_s);
    // GNSS (GnssPrior).
    h.emplace_back("ins.gnss.t_body_antenna",
                   Vector3([](Options* o) { return &o->ins.gnss.t_body_antenna; }));
    SLAM_MMS_KEY_D("ins.gnss.sigma_floor_horizontal_m", o->ins.gnss.sigma_floor_horizontal_m);
    SLAM_MMS_KEY_D("ins.gnss.sigma_floor_vertical_m", o->ins.gnss.sigma_floor_vertical_m);
    SLAM_MMS_KEY_D("ins.gnss.max_sigma_horizontal_m", o->ins.gnss.max_sigma_horizontal_m);
    h.emplace_back(
        "ins.gnss.min_fix_type",
        Enum<GnssFixType>([](Options* o) { return &o->ins.gnss.min_fix_type; }, FixTypeNames()));
    h.emplace_back("ins.gnss.full_weight_fix_type",
                   Enum<GnssFixType>([](Options* o) { return &o->ins.gnss.full_weight_fix_type; },
                                     FixTypeNames()));
    SLAM_MMS_KEY_D("ins.gnss.downweight_variance_factor", o->ins.gnss.downweight_variance_factor);
    SLAM_MMS_KEY_D("ins.gnss.innovation_downweight_chi2", o->ins.gnss.innovation_downweight_chi2);
    SLAM_MMS_KEY_D("ins.gnss.innovation_reject_chi2", o->ins.gnss.innovation_reject_chi2);
    SLAM_MMS_KEY_D("ins.gnss.max_rejection_streak_s", o->ins.gnss.max_rejection_streak_s);
    SLAM_MMS_KEY_D("ins.gnss.max_speed_mps", o->ins.gnss.max_speed_mps);
    SLAM_MMS_KEY_D("ins.gnss.outage_timeout_s", o->ins.gnss.outage_timeout_s);
    // Level 1 (Localizer).
    SLAM_MMS_KEY_D("localizer.submap_duration_s", o->localizer.submap_duration_s);
    SLAM_MMS_KEY_D("localizer.model_radius_m", o->localizer.model_radius_m);
    SLAM_MMS_KEY_F("localizer.min_model_confidence", o->localizer.min_model_confidence);
    SLAM_MMS_KEY_D("localizer.previous_submap_model_s", o->localizer.previous_submap_model_s);
    SLAM_MMS_KEY_D("localizer.odom_sigma_rot_rad", o->localizer.odom_sigma_rot_rad);
    SLAM_MMS_KEY_D("localizer.odom_sigma_trans_m", o->localizer.odom_sigma_trans_m);
    SLAM_MMS_KEY_D("localizer.cv_sigma_rot_rad", o->localizer.cv_sigma_rot_rad);
    SLAM_MMS_KEY_D("localizer.cv_sigma_trans_m", o->localizer.cv_sigma_trans_m);
    SLAM_MMS_KEY_D("localizer.reg_cov_scale", o->localizer.reg_cov_scale);
    SLAM_MMS_KEY_D("localizer.reg_sigma_floor_rot_rad", o->localizer.reg_sigma_floor_rot_rad);
    SLAM_MMS_KEY_D("localizer.reg_sigma_floor_trans_m", o->localizer.reg_sigma_floor_trans_m);
    SLAM_MMS_KEY_D("localizer.min_inlier_ratio", o->localizer.min_inlier_ratio);
    SLAM_MMS_KEY_D("localizer.map_voxel_m", o->localizer.map_voxel_m);
    SLAM_MMS_KEY_D("localizer.map_max_range_m", o->localizer.map_max_range_m);
    SLAM_MMS_KEY_D("localizer.registration_voxel_m", o->localizer.registration_voxel_m);
    SLAM_MMS_KEY_B("localizer.per_submap_surfels", o->localizer.per_submap_surfels);
    SLAM_MMS_KEY_B("localizer.archive_surfels", o->localizer.archive_surfels);
    h.emplace_back("localizer.spill_dir", Path([](Options* o) { return &o->localizer.spill_dir; }));
    SLAM_MMS_KEY_I("localizer.num_threads", o->localizer.num_threads);
    SLAM_MMS_KEY_I("localizer.surfels.renderer.projection.cols",
                   o->localizer.surfels.renderer.projection.cols);
    h.emplace_back("localizer.renderer",
                   Enum<SurfelRendererBackend>([](Options* o) { return &o->localizer.renderer; },
                                               {{"auto", SurfelRendererBackend::kAuto},
                                                {"cpu", SurfelRendererBackend::kCpu},
                                                {"egl", SurfelRendererBackend::kEgl}}));
    SLAM_MMS_KEY_D("localizer.icp.max_distance", o->localizer.icp.max_distance);
    SLAM_MMS_KEY_D("localizer.icp.max_angle_deg", o->localizer.icp.max_angle_deg);
    SLAM_MMS_KEY_D("localizer.icp.huber_delta", o->localizer.icp.huber_delta);
    SLAM_MMS_KEY_I("localizer.icp.max_iterations", o->localizer.icp.max_iterations);
    SLAM_MMS_KEY_I("localizer.icp.min_correspondences", o->localizer.icp.min_correspondences);
    SLAM_MMS_KEY_I("localizer.icp.pixel_stride", o->localizer.icp.pixel_stride);
    SLAM_MMS_KEY_D("localizer.surfels.max_distance_m", o->localizer.surfels.max_distance_m);
    SLAM_MMS_KEY_D("localizer.surfels.active_radius_m", o->localizer.surfels.active_radius_m);
    SLAM_MMS_KEY_I("localizer.window.window_size", o->localizer.window.window_size);
    SLAM_MMS_KEY_I("localizer.window.max_iterations", o->localizer.window.max_iterations);
    SLAM_MMS_KEY_D("localizer.window.max_solve_time_s", o->localizer.window.max_solve_time_s);
    SLAM_MMS_KEY_D("localizer.window.consistency_gate_chi2",
                   o->localizer.window.consistency_gate_chi2);
    // Level 2 (SubmapManager).
    SLAM_MMS_KEY_B("level2.enabled", o->level2.enabled);
    SLAM_MMS_KEY_B("level2.use_map_to_map", o->level2.use_map_to_map);
    SLAM_MMS_KEY_B("level2.use_gnss", o->level2.use_gnss);
    SLAM_MMS_KEY_B("level2.use_loops", o->level2.use_loops);
    SLAM_MMS_KEY_D("level2.loop_distance_m", o->level2.loop_distance_m);
    SLAM_MMS_KEY_I("level2.loop_min_submap_gap", o->level2.loop_min_submap_gap);
    SLAM_MMS_KEY_D("level2.loop_min_inlier_ratio", o->level2.loop_min_inlier_ratio);
    SLAM_MMS_KEY_D("level2.loop_max_rms_m", o->level2.loop_max_rms_m);
    SLAM_MMS_KEY_D("level2.loop_gate_chi2", o->level2.loop_gate_chi2);
    SLAM_MMS_KEY_D("level2.long_outage_s", o->level2.long_outage_s);
    SLAM_MMS_KEY_D("level2.reckon_sigma_rot_rad", o->level2.reckon_sigma_rot_rad);
    SLAM_MMS_KEY_D("level2.reckon_sigma_trans_m", o->level2.reckon_sigma_trans_m);
    SLAM_MMS_KEY_D("level2.gnss_sigma_scale", o->level2.gnss_sigma_scale);
    SLAM_MMS_KEY_D("level2.gnss_correlation_s", o->level2.gnss_correlation_s);
    SLAM_MMS_KEY_I("level2.max_iterations", o->level2.max_iterations);
    SLAM_MMS_KEY_I("level2.num_threads", o->level2.num_threads);
#undef SLAM_MMS_KEY_D
#undef SLAM_MMS_KEY_F
#undef SLAM_MMS_KEY_I
#undef SLAM_MMS_KEY_B
    return h;
  }();
  return kHandlers;
}

const KeyHandler* FindHandler(const std::string& key) {
  for (const auto& [name, handler] : Handlers()) {
    if (name == key) return &handler;
  }
  return nullptr;
}

}  // namespace

std::vector<ConfigKeyInfo> ConfigKeys() {
  const Options defaults;
  std::vector<ConfigKeyInfo> keys;
  for (const auto& [name, handler] : Handlers()) {
    keys.push_back({name, handler.type, handler.get(defaults)});
  }
  return keys;
}

Status ApplyConfigText(const std::string& text, const std::string& file_name, Options* options) {
  std::istringstream in(text);
  std::string line;
  int line_number = 0;
  std::set<std::string> seen;
  int origin_keys = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    line = Trim(line);
    if (line.empty()) continue;
    const std::string where = file_name + ":" + std::to_string(line_number) + ": ";
    const size_t eq = line.find('=');
    if (eq == std::string::npos) {
      return InvalidArgumentError(where + "expected 'key = value', got '" + line + "'");
    }
    const std::string key = Trim(line.substr(0, eq));
    const std::string value = Trim(line.substr(eq + 1));
    if (key.empty()) return InvalidArgumentError(where + "missing key before '='");
    const KeyHandler* handler = FindHandler(key);
    if (handler == nullptr) {
      return InvalidArgumentError(where + "unknown key '" + key +
                                  "' (the keys are listed in docs/user_guide.md, \"Options\")");
    }
    if (!seen.insert(key).second) {
      return InvalidArgumentError(where + "key '" + key + "' given twice");
    }
    if (!handler->set(value, options)) {
      return InvalidArgumentError(where + "key '" + key + "': bad value '" + value +
                                  "' (expected " + handler->type + ")");
    }
    if (key.rfind("origin_", 0) == 0) ++origin_keys;
  }
  if (origin_keys != 0 && origin_keys != 3) {
    return InvalidArgumentError(file_name +
                                ": origin_latitude_deg, origin_longitude_deg and origin_height_m "
                                "must be given together");
  }
  const Status valid = options->Validate();
  if (!valid.ok()) return InvalidArgumentError(file_name + ": " + valid.message());
  return OkStatus();
}

Status ApplyConfigFile(const std::filesystem::path& file, Options* options) {
  std::ifstream in(file);
  if (!in) return NotFoundError(file.string() + ": cannot open the config file");
  std::ostringstream text;
  text << in.rdbuf();
  return ApplyConfigText(text.str(), file.string(), options);
}

}  // namespace slam_mms::app
