#pragma once
// The --config file of slam_mms_run: a YAML mapping overriding MappingSystem::Options fields and,
// under drive.*, the drive runner's DriveRunOptions (RunConfig).
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
// its message (field and rule) is prefixed with the file name. Keys that moved name their new
// place (level2.estimate_extrinsics -> drive.estimate_extrinsics).
//
// OptionsToYaml() writes every key with its value and a "# type; default D" comment in this
// format: --dump-config and --config-keys print it, and ApplyConfigText() reads it back to the same
// options (dump, read, dump again gives the same bytes). OptionsToJson() gives the same tree as a
// JSON object (report.json's "options").

#include <filesystem>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"

namespace slam_mms::app {

/// What a --config file sets: the MappingSystem's options (every key but drive.*) and the drive
/// runner's (drive.*: what RunDrive does over the whole drive besides streaming it).
struct RunConfig {
  MappingSystem::Options system;
  DriveRunOptions drive;
  /// system.Validate(), then drive.Validate().
  [[nodiscard]] Status Validate() const;
};

/// Applies the file's overrides to `config` and validates the result.
Status ApplyConfigFile(const std::filesystem::path& file, RunConfig* config);
/// The same on text already read; `file_name` is used in messages.
Status ApplyConfigText(const std::string& text, const std::string& file_name, RunConfig* config);
/// For a caller that takes only MappingSystem options (slam_mms_sweep, slam_mms_sim_realism, the
/// Python package's apply_config_file): as above, and InvalidArgument naming the file where it
/// sets a drive.* key to anything but its default (the caller would ignore it).
Status ApplyConfigFile(const std::filesystem::path& file, MappingSystem::Options* options);
Status ApplyConfigText(const std::string& text, const std::string& file_name,
                       MappingSystem::Options* options);

/// Every config key of `config` as YAML (nested block mappings in ConfigKeys() order), each line
/// commented with the key's type and default; ApplyConfigText() reads it back unchanged.
std::string OptionsToYaml(const RunConfig& config);
/// Writes OptionsToYaml(config) to `file` (fails naming the file).
Status WriteConfigFile(const RunConfig& config, const std::filesystem::path& file);
/// The same keys and values as one JSON object text (nested like the YAML; vectors as arrays,
/// unset origin/paths as null), for report.json's "options".
std::string OptionsToJson(const RunConfig& config);
/// The same with the drive.* keys at their defaults.
std::string OptionsToYaml(const MappingSystem::Options& options);
Status WriteConfigFile(const MappingSystem::Options& options, const std::filesystem::path& file);
std::string OptionsToJson(const MappingSystem::Options& options);

struct ConfigKeyInfo {
  std::string key;
  std::string type;           ///< "double", "int", "bool", "vector3", "path" or "enum: a|b|c".
  std::string default_value;  ///< As written in the YAML ("~" = unset).
};
/// Every key the file accepts, with its type and its default (for docs and --help).
std::vector<ConfigKeyInfo> ConfigKeys();

}  // namespace slam_mms::app
