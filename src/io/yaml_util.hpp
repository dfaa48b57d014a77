#pragma once
// Private helpers of the io module's YAML readers (extrinsics.yaml, imu_noise.yaml): the file's
// one document, where a node is ("<file>:<line>") and a finite number read from a scalar node,
// with the one error wording.

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "io/file_util.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::io_internal {

/// "<file>:<line>" of `node` (1-based), or `file` where the node has no mark.
inline std::string YamlWhere(const std::string& file, const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? file : file + ":" + std::to_string(mark.line + 1);
}

/// The one YAML document of `text`; a null node for an empty text. yaml-cpp's Load keeps the first
/// document and drops the rest without a word (`{}` and then `key: value` on the next line are
/// two documents, as are two maps split by `---`): a second one is kDataLoss naming its line.
/// Throws YAML::ParserException as YAML::Load does.
inline StatusOr<YAML::Node> YamlOneDocument(const std::string& text, const std::string& file) {
  std::vector<YAML::Node> docs = YAML::LoadAll(text);
  if (docs.empty()) return YAML::Node();
  if (docs.size() > 1) {
    return DataLossError(YamlWhere(file, docs[1]) +
                         ": a second YAML document (the file must be one mapping; is a line left "
                         "after a closed '{...}', or a '---'?)");
  }
  return docs.front();
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
