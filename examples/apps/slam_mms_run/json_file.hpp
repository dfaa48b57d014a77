#pragma once
// JSON files of the apps (slam_mms_run's checkpoint, slam_mms_sweep's specs and results):
// read whole, and written beside then renamed, so that a kill while writing never leaves a half
// file behind.

#include <filesystem>
#include <nlohmann/json.hpp>

#include "slam_mms/core/status.hpp"

namespace slam_mms::app {

/// kNotFound when the file cannot be opened, kDataLoss naming it when it is not valid JSON.
StatusOr<nlohmann::json> ReadJsonFile(const std::filesystem::path& file);

/// `j.dump(indent)` and a newline into `file` (through `file`.tmp); kUnavailable naming the file.
Status WriteJsonFile(const nlohmann::json& j, const std::filesystem::path& file, int indent);

}  // namespace slam_mms::app
