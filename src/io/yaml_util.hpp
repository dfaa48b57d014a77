#pragma once
// Private helpers of the io module's YAML readers (extrinsics.yaml, imu_noise.yaml): where a node
// is ("<file>:<line>") and a finite number read from a scalar node, with the one error wording.

#include <yaml-cpp/yaml.h>

#include <string>

#include "io/file_util.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::io_internal {

/// "<file>:<line>" of `node` (1-based), or `file` where the node has no mark.
inline std::string YamlWhere(const std::string& file, const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? file : file + ":" + std::to_string(mark.line + 1);
}

/// `node` as a finite number; else kDataLoss "<what> '<text>' is not a finite number<suffix>"
/// (`what` names where and which key; `suffix` e.g. " [s]").
inline Status YamlFiniteNumber(const YAML::Node& node, const std::string& what,
                               const std::string& suffix, double* value) {
  if (node.IsScalar() && ParseDouble(node.Scalar(), value)) return OkStatus();
  return DataLossError(what + " '" +
                       (node.IsScalar() ? node.Scalar() : std::string("(not a scalar)")) +
                       "' is not a finite number" + suffix);
}

}  // namespace slam_mms::io_internal
