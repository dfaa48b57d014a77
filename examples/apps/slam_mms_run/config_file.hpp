#pragma once
// The --config file of slam_mms_run: "key = value" lines overriding MappingSystem::Options fields.
// '#' starts a comment; blank lines are ignored; keys are the option paths
// ("localizer.submap_duration_s", "ins.gnss.outage_timeout_s", "level2.use_loops", ...; the full
// list is ConfigKeys() and docs/user_guide.md "Options"). Values: numbers, integers, booleans
// (true/false/1/0/yes/no/on/off), vectors of three numbers ("0 0 0.75") or enum names.
// Errors name the file, the line and the key: an unknown key, a value that does not parse, a key
// given twice; then MappingSystem::Options::Validate() runs and its message (field and rule) is
// prefixed with the file name.

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

struct ConfigKeyInfo {
  std::string key;
  std::string type;  ///< "double", "int", "bool", "vector3", or "enum: a|b|c".
  std::string default_value;
};
/// Every key the file accepts, with its type and its default (for docs and --help).
std::vector<ConfigKeyInfo> ConfigKeys();

}  // namespace slam_mms::app
