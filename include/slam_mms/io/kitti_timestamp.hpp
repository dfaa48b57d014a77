#pragma once
// KITTI timestamp strings ("2011-09-26 13:02:25.964389445", UTC) <-> Timestamp, nanosecond exact.
// Formatting is Timestamp::ToKittiString() (core); parsing lives here.
//
// Thread safety: pure functions; safe from any thread.

#include <string>
#include <string_view>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms {

/// Parses "YYYY-MM-DD hh:mm:ss[.fffffffff]" (UTC; 0 to 9 fraction digits; surrounding whitespace
/// and a trailing '\r' allowed) exactly to nanoseconds. kInvalidArgument names the text and the
/// part that is wrong ("month 13 out of 1..12").
[[nodiscard]] StatusOr<Timestamp> ParseKittiTimestamp(std::string_view text);

}  // namespace slam_mms
