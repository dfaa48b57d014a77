#include "slam_mms_run/config_file.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "slam_mms/pipeline/sensor_presets.hpp"
#include "slam_mms/version.hpp"
#include "slam_mms_run/config_keys.hpp"

namespace slam_mms::app {
namespace {

using config::Handlers;
using config::Json;
using config::KeyHandler;
using Options = RunConfig;

// Keys that moved (issue #19: the calibration is the drive runner's, not level 2's).
const char* MovedTo(const std::string& key) {
  static const std::pair<const char*, const char*> kMoved[] = {
      {"level2.estimate_extrinsics", "drive.estimate_extrinsics"},
      {"level2.extrinsic_calibration.attitude_reference",
       "drive.extrinsic_calibration.attitude_reference"},
      {"level2.extrinsic_calibration.max_scans", "drive.extrinsic_calibration.max_scans"},
      {"level2.extrinsic_calibration", "drive.extrinsic_calibration"}};
  for (const auto& [from, to] : kMoved) {
    if (key == from) return to;
  }
  return nullptr;
}

const KeyHandler* FindHandler(const std::string& key) {
  for (const auto& [name, handler] : Handlers()) {
    if (name == key) return &handler;
  }
  return nullptr;
}

// True where `prefix` is a group of keys ("localizer", "ins.gnss"): some key starts with "prefix.".
bool IsGroup(const std::string& prefix) {
  const std::string dotted = prefix + ".";
  for (const auto& [name, handler] : Handlers()) {
    if (name.compare(0, dotted.size(), dotted) == 0) return true;
  }
  return false;
}

std::string NodeKind(const YAML::Node& n) {
  if (n.IsMap()) return "a mapping";
  if (n.IsSequence()) return "a list";
  if (n.IsNull()) return "no value";
  return "'" + n.Scalar() + "'";
}

struct ParseState {
  std::string file_name;
  std::set<std::string> seen;
  int origin_numbers = 0;
  int origin_nulls = 0;
};

std::string Where(const ParseState& s, const YAML::Node& node) {
  return s.file_name + ":" + std::to_string(node.Mark().line + 1) + ": ";
}

// Applies one mapping whose keys are relative to `prefix` ("" at the top).
Status ApplyMapping(const YAML::Node& map, const std::string& prefix, ParseState* state,
                    Options* options) {
  for (auto it = map.begin(); it != map.end(); ++it) {
    const YAML::Node& key_node = it->first;
    const YAML::Node& value = it->second;
    const std::string where = Where(*state, key_node);
    if (!key_node.IsScalar() || key_node.Scalar().empty()) {
      return InvalidArgumentError(where + "expected a key name, got " + NodeKind(key_node));
    }
    const std::string key = prefix.empty() ? key_node.Scalar() : prefix + "." + key_node.Scalar();
    if (key == "preset") continue;  // applied first (ApplyPreset)
    const KeyHandler* handler = FindHandler(key);
    if (handler == nullptr) {
      if (IsGroup(key)) {
        if (!value.IsMap()) {
          return InvalidArgumentError(where + "'" + key +
                                      "' is a group of keys: expected a mapping, got " +
                                      NodeKind(value));
        }
        SLAM_MMS_RETURN_IF_ERROR(ApplyMapping(value, key, state, options));
        continue;
      }
      if (const char* to = MovedTo(key)) {
        return InvalidArgumentError(where + "key '" + key + "' moved to '" + to + "'");
      }
      return InvalidArgumentError(where + "unknown key '" + key +
                                  "' (slam_mms_run --config-keys lists them; docs/user_guide.md, "
                                  "\"Options\")");
    }
    if (!state->seen.insert(key).second) {
      return InvalidArgumentError(where + "key '" + key + "' given twice");
    }
    if (value.IsMap() || (value.IsSequence() && !handler->sequence) ||
        (value.IsNull() && !handler->nullable)) {
      return InvalidArgumentError(where + "key '" + key + "': expected " + handler->type +
                                  ", got " + NodeKind(value));
    }
    if (!handler->set(value, options)) {
      std::string text = value.IsScalar() ? value.Scalar() : "";
      if (value.IsSequence()) {
        YAML::Emitter e;
        e << YAML::Flow << value;
        text = e.c_str();
      }
      return InvalidArgumentError(where + "key '" + key + "': bad value '" + text + "' (expected " +
                                  handler->type + ")");
    }
    if (key.rfind("origin_", 0) == 0)
      ++(value.IsNull() ? state->origin_nulls : state->origin_numbers);
  }
  return OkStatus();
}

// The keys as a tree, children in first-appearance order of ConfigKeys(): what OptionsToYaml and
// OptionsToJson walk.
struct KeyTree {
  std::string name;
  const KeyHandler* handler = nullptr;  ///< Leaves only.
  std::string full_key;
  std::vector<KeyTree> children;
  KeyTree* Child(const std::string& child_name) {
    for (KeyTree& c : children) {
      if (c.name == child_name && c.handler == nullptr) return &c;
    }
    children.push_back({child_name, nullptr, "", {}});
    return &children.back();
  }
};

const KeyTree& Tree() {
  static const KeyTree kTree = [] {
    KeyTree root;
    for (const auto& [name, handler] : Handlers()) {
      KeyTree* node = &root;
      size_t begin = 0;
      for (size_t dot = name.find('.'); dot != std::string::npos; dot = name.find('.', begin)) {
        node = node->Child(name.substr(begin, dot - begin));
        begin = dot + 1;
      }
      node->children.push_back({name.substr(begin), &handler, name, {}});
    }
    return root;
  }();
  return kTree;
}

void WriteYaml(const KeyTree& node, const Options& options, const Options& defaults, int depth,
               std::string* out) {
  const std::string indent(static_cast<size_t>(2 * depth), ' ');
  for (const KeyTree& c : node.children) {
    if (c.handler == nullptr) {
      *out += indent + c.name + ":\n";
      WriteYaml(c, options, defaults, depth + 1, out);
      continue;
    }
    std::string type = c.handler->type;
    if (c.handler->nullable && c.full_key.rfind("origin_", 0) == 0) {
      type += " or ~ (all three ~: the first valid GNSS fix)";
    } else if (c.handler->nullable) {
      type += " or ~ (unset)";
    }
    *out += indent + c.name + ": " + c.handler->yaml(options) + "  # " + type + "; default " +
            c.handler->yaml(defaults) + "\n";
  }
}

Json ToJson(const KeyTree& node, const Options& options) {
  Json object = Json::object();
  for (const KeyTree& c : node.children) {
    object[c.name] = c.handler == nullptr ? ToJson(c, options) : c.handler->json(options);
  }
  return object;
}

}  // namespace

std::vector<ConfigKeyInfo> ConfigKeys() {
  const Options defaults;
  std::vector<ConfigKeyInfo> keys;
  for (const auto& [name, handler] : Handlers()) {
    keys.push_back({name, handler.type, handler.yaml(defaults)});
  }
  return keys;
}

// The top-level `preset` key: the sensor's image geometry, applied before every other key so that
// the file's own keys override it wherever they stand.
Status ApplyPreset(const YAML::Node& root, const ParseState& state, Options* options) {
  const YAML::Node& croot = root;
  const YAML::Node preset = croot["preset"];
  if (!preset) return OkStatus();
  const std::string where = Where(state, preset);
  if (!preset.IsScalar()) {
    return InvalidArgumentError(where + "key 'preset': expected a sensor name, got " +
                                NodeKind(preset));
  }
  auto parsed = ParseLidarPreset(preset.Scalar());
  if (!parsed.ok()) return InvalidArgumentError(where + "key " + parsed.status().message());
  ApplyLidarPreset(*parsed, &options->system);
  return OkStatus();
}

Status ApplyConfigText(const std::string& text, const std::string& file_name, Options* options) {
  // Every document: yaml-cpp's Load keeps the first and drops the rest without a word (`{}` and
  // then `key: value` on the next line are two documents).
  std::vector<YAML::Node> docs;
  try {
    docs = YAML::LoadAll(text);
  } catch (const YAML::ParserException& e) {
    return InvalidArgumentError(file_name + ":" + std::to_string(e.mark.line + 1) +
                                ": not valid YAML: " + e.msg);
  }
  ParseState state;
  state.file_name = file_name;
  if (docs.size() > 1) {
    return InvalidArgumentError(Where(state, docs[1]) +
                                "a second YAML document (a config file is one mapping; is a line "
                                "left after a closed '{...}', or a '---'?)");
  }
  const YAML::Node root = docs.empty() ? YAML::Node() : docs.front();
  if (root.IsMap()) {
    try {
      SLAM_MMS_RETURN_IF_ERROR(ApplyPreset(root, state, options));
      SLAM_MMS_RETURN_IF_ERROR(ApplyMapping(root, "", &state, options));
    } catch (const YAML::Exception& e) {
      return InvalidArgumentError(file_name + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
    }
  } else if (!root.IsNull()) {  // An empty file (or only comments) overrides nothing.
    return InvalidArgumentError(Where(state, root) +
                                "expected a mapping of option keys to values (key: value), got " +
                                NodeKind(root));
  }
  if (state.origin_numbers != 0 && state.origin_numbers != 3) {
    return InvalidArgumentError(file_name +
                                ": origin_latitude_deg, origin_longitude_deg and origin_height_m "
                                "must be given together (three numbers, or ~ for all three)");
  }
  if (state.origin_numbers == 0 && state.origin_nulls > 0) options->system.origin.reset();
  const Status valid = options->Validate();
  if (!valid.ok()) return InvalidArgumentError(file_name + ": " + valid.message());
  return OkStatus();
}

Status ApplyConfigFile(const std::filesystem::path& file, Options* options) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return NotFoundError(file.string() + ": cannot open the config file");
  std::ostringstream text;
  text << in.rdbuf();
  return ApplyConfigText(text.str(), file.string(), options);
}

std::string OptionsToYaml(const Options& options) {
  std::string out =
      "# slam_mms_run options (slam_mms " SLAM_MMS_VERSION_STRING
      "): every --config key with its value.\n"
      "# `slam_mms_run --config FILE` reads this file back; keep only the keys you change.\n"
      "# Nested keys may also be written dotted (localizer.submap_duration_s: 2.0).\n";
  WriteYaml(Tree(), options, Options(), 0, &out);
  return out;
}

Status WriteConfigFile(const Options& options, const std::filesystem::path& file) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) return NotFoundError(file.string() + ": cannot open for writing");
  out << OptionsToYaml(options);
  out.close();
  if (!out) return DataLossError(file.string() + ": failed writing");
  return OkStatus();
}

std::string OptionsToJson(const Options& options) { return ToJson(Tree(), options).dump(); }

Status RunConfig::Validate() const {
  SLAM_MMS_RETURN_IF_ERROR(system.Validate());
  return drive.Validate();
}

namespace {

// The system-only hosts: the file's drive.* keys must stay at their defaults.
Status SystemOnly(const RunConfig& config, const std::string& file_name,
                  MappingSystem::Options* options) {
  const Json drive = ToJson(Tree(), config)["drive"];
  const Json defaults = ToJson(Tree(), RunConfig())["drive"];
  if (drive != defaults) {
    return InvalidArgumentError(file_name +
                                ": drive.* keys set the drive runner (slam_mms_run's "
                                "DriveRunOptions), which this caller does not take; leave them at "
                                "their defaults here");
  }
  *options = config.system;
  return OkStatus();
}

}  // namespace

Status ApplyConfigFile(const std::filesystem::path& file, MappingSystem::Options* options) {
  RunConfig config;
  config.system = *options;
  SLAM_MMS_RETURN_IF_ERROR(ApplyConfigFile(file, &config));
  return SystemOnly(config, file.string(), options);
}

Status ApplyConfigText(const std::string& text, const std::string& file_name,
                       MappingSystem::Options* options) {
  RunConfig config;
  config.system = *options;
  SLAM_MMS_RETURN_IF_ERROR(ApplyConfigText(text, file_name, &config));
  return SystemOnly(config, file_name, options);
}

std::string OptionsToYaml(const MappingSystem::Options& options) {
  RunConfig config;
  config.system = options;
  return OptionsToYaml(config);
}

Status WriteConfigFile(const MappingSystem::Options& options, const std::filesystem::path& file) {
  RunConfig config;
  config.system = options;
  return WriteConfigFile(config, file);
}

std::string OptionsToJson(const MappingSystem::Options& options) {
  RunConfig config;
  config.system = options;
  return OptionsToJson(config);
}

}  // namespace slam_mms::app
