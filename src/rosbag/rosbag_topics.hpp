#pragma once
// Private: the topics of a ROS 1 bag and the choice of one per stream, for RosbagDriveReader
// (split from rosbag_drive_reader.cpp).
//
// Thread safety: pure functions (a rosbag::Bag is read, not shared).

#include <rosbag/bag.h>

#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/rosbag/rosbag_drive_reader.hpp"

namespace slam_mms::rosbag_internal {

/// "the bag has: /a [type, n messages], ..." (for messages).
std::string TopicList(const std::vector<RosbagTopic>& topics);

/// Every topic of `bag` with its datatype and message count, by name.
std::vector<RosbagTopic> TopicsOf(const rosbag::Bag& bag);

/// The topic for one stream: `requested` (checked to exist with `datatype`), else the only topic
/// of `datatype`. An empty string where none exists and `required` is false; InvalidArgument
/// naming `bag`, the option and the bag's topics otherwise.
StatusOr<std::string> ChooseTopic(const std::vector<RosbagTopic>& topics,
                                  const std::string& requested, const char* datatype,
                                  const char* option, bool required, const std::string& bag);

}  // namespace slam_mms::rosbag_internal
