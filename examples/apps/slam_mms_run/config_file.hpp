#pragma once
// The --config file of slam_mms_run: a YAML mapping overriding MappingSystem::Options fields.
// Keys are the option paths ("localizer.submap_duration_s", "ins.gnss.outage_timeout_s",
// "level2.use_loops", ...; the full list is ConfigKeys(), `slam_mms_run --config-keys` and
// docs/user_guide.md "Options"), written as nested block mappings or as dotted keys, mixed freely:
//
//   localizer:
//     submap_duration_s: 2.0
//     icp: {max_iterations: 30}
//   level2.use_loops: false
//
// A top-level `preset: NAME` (hdl64e, hdl32e, vlp16, os1_64; sensor_presets.hpp) sets the sensor's
// range-image geometry first, wherever it stands; the file's other keys override it. It is not
// written back: --dump-config writes the resulting values.
//
// Values: numbers (double), integers (int), booleans (true/false/yes/no/on/off/1/0), vectors of
// three numbers ([0, 0, 0.75]), enum names, paths (a string; ~ or none = unset). The origin keys
// take ~ for "unset" (the first valid GNSS fix) and go together (all three numbers or none).
// Errors name the file, the line and the key: a YAML syntax error, an unknown key, a value of the
// wrong type (a mapping or list where a number is expected), a value that does not parse, a key
// given twice (also once nested and once dotted); then MappingSystem::Options::Validate() runs and
// its message (field and rule) is prefixed with the file name.
//
// OptionsToYaml() writes every key with its value and a "# type; default D" comment in this
// format: --dump-config and --config-keys print it, and ApplyConfigText() reads it back to the same
// options (dump, read, dump again gives the same bytes). OptionsToJson() gives the same tree as a
// JSON object (report.json's "options").

#include <filesystem>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"

namespace slam_mms::app {

/// Applies the file's overrides to `options` and validates the result.
Status ApplyConfigFile(const std::filesystem::path& file, MappingSystem::Options* options);
/// The same on text already read; `file_name` is used in messages.
Status ApplyConfigText(const std::string& text, const std::string& file_name,
                       MappingSystem::Options* options);

/// Every config key of `options` as YAML (nested block mappings in ConfigKeys() order), each line
/// commented with the key's type and default; ApplyConfigText() reads it back unchanged.
std::string OptionsToYaml(const MappingSystem::Options& options);
/// Writes OptionsToYaml(options) to `file` (fails naming the file).
Status WriteConfigFile(const MappingSystem::Options& options, const std::filesystem::path& file);
/// The same keys and values as one JSON object text (nested like the YAML; vectors as arrays,
/// unset origin/paths as null), for report.json's "options".
std::string OptionsToJson(const MappingSystem::Options& options);

struct ConfigKeyInfo {
  std::string key;
  std::string type;           ///< "double", "int", "bool", "vector3", "path" or "enum: a|b|c".
  std::string default_value;  ///< As written in the YAML ("~" = unset).
};
/// Every key the file accepts, with its type and its default (for docs and --help).
std::vector<ConfigKeyInfo> ConfigKeys();

}  // namespace slam_mms::app
