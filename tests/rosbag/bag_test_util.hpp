#pragma once
// Test helpers: small ROS 1 bags written with rosbag::Bag directly (malformed ones included).
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace slam_mms::testing {

constexpr int64_t kBagT0Ns = 1317000000LL * 1000000000LL;

inline ros::Time RosTimeNs(int64_t ns) {
  ros::Time t;
  t.fromNSec(static_cast<uint64_t>(ns));
  return t;
}

/// Writes `bag` through `fill` (rosbag exceptions fail the test through gtest's handler).
inline void WriteTestBag(const std::filesystem::path& bag,
                         const std::function<void(rosbag::Bag&)>& fill) {
  rosbag::Bag b(bag.string(), rosbag::bagmode::Write);
  fill(b);
  b.close();
}

inline sensor_msgs::Imu TestImu(int64_t ns) {
  sensor_msgs::Imu m;
  m.header.stamp = RosTimeNs(ns);
  m.orientation.w = 1.0;
  m.orientation_covariance[0] = -1.0;
  m.linear_acceleration.z = 9.81;
  return m;
}

/// A field of a hand-made cloud.
struct TestField {
  std::string name;
  uint32_t offset;
  uint8_t datatype;
};

/// A cloud of `width` x `height` points of `point_step` bytes (row_step = width * point_step +
/// row_padding); `put(point_index, bytes)` fills each point.
inline sensor_msgs::PointCloud2 TestCloud(int64_t stamp_ns, const std::vector<TestField>& fields,
                                          uint32_t point_step, uint32_t width, uint32_t height,
                                          const std::function<void(size_t, uint8_t*)>& put,
                                          uint32_t row_padding = 0) {
  sensor_msgs::PointCloud2 m;
  m.header.stamp = RosTimeNs(stamp_ns);
  m.header.frame_id = "lidar";
  for (const TestField& f : fields) {
    sensor_msgs::PointField pf;
    pf.name = f.name;
    pf.offset = f.offset;
    pf.datatype = f.datatype;
    pf.count = 1;
    m.fields.push_back(pf);
  }
  m.height = height;
  m.width = width;
  m.point_step = point_step;
  m.row_step = width * point_step + row_padding;
  m.is_bigendian = false;
  m.is_dense = true;
  m.data.assign(static_cast<size_t>(m.row_step) * height, 0);
  for (uint32_t r = 0; r < height; ++r) {
    for (uint32_t c = 0; c < width; ++c) {
      put(static_cast<size_t>(r) * width + c, m.data.data() + r * m.row_step + c * point_step);
    }
  }
  return m;
}

template <typename T>
void Put(uint8_t* p, uint32_t offset, T v) {
  std::memcpy(p + offset, &v, sizeof(T));
}

/// x y z intensity float32 cloud of n points on a circle (no time field).
inline sensor_msgs::PointCloud2 SimpleCloud(int64_t stamp_ns, uint32_t n) {
  using sensor_msgs::PointField;
  return TestCloud(stamp_ns,
                   {{"x", 0, PointField::FLOAT32},
                    {"y", 4, PointField::FLOAT32},
                    {"z", 8, PointField::FLOAT32},
                    {"intensity", 12, PointField::FLOAT32}},
                   16, n, 1, [n](size_t k, uint8_t* p) {
                     const double a = 2.0 * M_PI * static_cast<double>(k) / n;
                     Put<float>(p, 0, static_cast<float>(10.0 * std::cos(a)));
                     Put<float>(p, 4, static_cast<float>(10.0 * std::sin(a)));
                     Put<float>(p, 8, 0.5f);
                     Put<float>(p, 12, 0.25f);
                   });
}

}  // namespace slam_mms::testing
