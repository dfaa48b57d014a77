#include "core/option_error.hpp"

#include <cstdio>
#include <string>
#include <utility>

namespace slam_mms::internal {

Status OptionError(std::string_view owner, std::string_view field, double value,
                   std::string_view rule) {
  char number[32];
  std::snprintf(number, sizeof(number), "%.6g", value);
  std::string m;
  m.reserve(owner.size() + field.size() + rule.size() + 40);
  m.append(owner).append("::").append(field).append(" = ").append(number).append("; ").append(rule);
  return InvalidArgumentError(std::move(m));
}

}  // namespace slam_mms::internal
