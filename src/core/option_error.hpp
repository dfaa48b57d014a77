#pragma once
// OptionError: the one message format of the library's Options::Validate() errors (issue #19):
//   "<owner>::<field> = <value>; <rule>"    e.g. "Localizer::Options::num_threads = 0; must be >=
//   1"
// The value is printed as %.6g ("0", "1.5", "0.006", "nan", "1e+09"), integers exactly up to 6
// digits. Returns kInvalidArgument.
//
// Thread safety: a pure function.

#include <string_view>

#include "slam_mms/core/status.hpp"

namespace slam_mms::internal {

Status OptionError(std::string_view owner, std::string_view field, double value,
                   std::string_view rule);

}  // namespace slam_mms::internal
