#pragma once
// The keys of slam_mms_run's --config file (config_file.hpp): for each option path, how a YAML
// value sets the RunConfig field (MappingSystem::Options, or DriveRunOptions for drive.*) and how
// the field is written back as YAML and JSON.
// Private to the app (config_file.cpp, the Python package's apply_config_file, slam_mms_sweep).

#include <yaml-cpp/yaml.h>

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "slam_mms_run/config_file.hpp"

namespace slam_mms::app::config {

using Options = RunConfig;
using Json = nlohmann::ordered_json;

// One accepted key: how to parse a YAML value into the options, and how to write the current value
// as YAML text and as JSON.
struct KeyHandler {
  std::string type;
  /// Sets the field from a scalar (or, for vector3, a sequence or scalar); false: bad value.
  std::function<bool(const YAML::Node& value, Options* o)> set;
  std::function<std::string(const Options& o)> yaml;
  std::function<Json(const Options& o)> json;
  bool nullable = false;  ///< `~` is a value (unset origin, no path).
  bool sequence = false;  ///< Takes a list (vector3).
};

/// Every key in ConfigKeys() order (the order of --dump-config).
const std::vector<std::pair<std::string, KeyHandler>>& Handlers();

}  // namespace slam_mms::app::config
