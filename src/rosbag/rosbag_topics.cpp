#include "rosbag/rosbag_topics.hpp"

#include <rosbag/view.h>

#include <map>

namespace slam_mms::rosbag_internal {

std::string TopicList(const std::vector<RosbagTopic>& topics) {
  if (topics.empty()) return "the bag has no topics";
  std::string s = "the bag has: ";
  for (size_t k = 0; k < topics.size(); ++k) {
    const RosbagTopic& t = topics[k];
    s += (k > 0 ? ", " : "") + t.name + " [" + t.datatype + ", " + std::to_string(t.num_messages) +
         " messages]";
  }
  return s;
}

std::vector<RosbagTopic> TopicsOf(const rosbag::Bag& bag) {
  std::map<std::string, RosbagTopic> by_name;
  rosbag::View all(bag);
  for (const rosbag::ConnectionInfo* c : all.getConnections()) {
    RosbagTopic& t = by_name[c->topic];
    t.name = c->topic;
    if (t.datatype.empty()) t.datatype = c->datatype;
  }
  std::vector<RosbagTopic> topics;
  for (auto& [name, t] : by_name) {
    rosbag::View v(bag, rosbag::TopicQuery(name));
    t.num_messages = v.size();
    topics.push_back(t);
  }
  return topics;
}

StatusOr<std::string> ChooseTopic(const std::vector<RosbagTopic>& topics,
                                  const std::string& requested, const char* datatype,
                                  const char* option, bool required, const std::string& bag) {
  if (!requested.empty()) {
    for (const RosbagTopic& t : topics) {
      if (t.name != requested) continue;
      if (t.datatype != datatype) {
        return InvalidArgumentError(bag + ": topic " + requested + " (Options::" + option +
                                    ") is " + t.datatype + ", not " + datatype + "; " +
                                    TopicList(topics));
      }
      return requested;
    }
    return InvalidArgumentError(bag + ": topic " + requested + " (Options::" + option +
                                ") is not in the bag; " + TopicList(topics));
  }
  std::vector<std::string> candidates;
  for (const RosbagTopic& t : topics) {
    if (t.datatype == datatype) candidates.push_back(t.name);
  }
  if (candidates.size() == 1) return candidates.front();
  if (candidates.empty()) {
    if (!required) return std::string();
    return InvalidArgumentError(bag + ": no " + datatype + " topic for Options::" + option + "; " +
                                TopicList(topics));
  }
  std::string names;
  for (const std::string& c : candidates) names += (names.empty() ? "" : ", ") + c;
  return InvalidArgumentError(bag + ": " + std::to_string(candidates.size()) + " " + datatype +
                              " topics (" + names + "): choose one with Options::" + option + "; " +
                              TopicList(topics));
}

}  // namespace slam_mms::rosbag_internal
