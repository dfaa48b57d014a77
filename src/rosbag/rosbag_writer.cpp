#include "slam_mms/rosbag/rosbag_writer.hpp"

#include <geometry_msgs/TwistStamped.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/NavSatFix.h>
#include <sensor_msgs/PointCloud2.h>

#include <system_error>

#include "rosbag/point_cloud2_codec.hpp"
#include "rosbag/ros_conversions.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {
namespace {

Status CheckTopic(const char* option, const std::string& topic) {
  if (topic.empty() || topic.find_first_of(" \t\n") != std::string::npos) {
    return InvalidArgumentError(std::string("RosbagWriteOptions::") + option + " = '" + topic +
                                "'; must be a non-empty topic name without spaces");
  }
  return OkStatus();
}

// The IMU message that carries the initial attitude: the one at its stamp, else the first.
size_t AttitudeMessage(const DriveStreams& s) {
  if (!s.initial_state) return 0;
  for (size_t k = 0; k < s.imu.size(); ++k) {
    if (s.imu[k].stamp == s.initial_state->stamp) return k;
  }
  return 0;
}

Status WriteStreams(const DriveStreams& s, const RosbagWriteOptions& o, rosbag::Bag* bag) {
  const size_t attitude_k = AttitudeMessage(s);
  if (s.initial_state && !s.imu.empty() && s.imu[attitude_k].stamp != s.initial_state->stamp) {
    SLAM_MMS_LOG(kInfo) << "WriteRosbag: no IMU sample at the initial state's stamp "
                        << s.initial_state->stamp.ToKittiString()
                        << ": its attitude goes on the first IMU message";
  }
  for (size_t k = 0; k < s.imu.size(); ++k) {
    const ImuSample& x = s.imu[k];
    sensor_msgs::Imu msg;
    msg.header.seq = static_cast<uint32_t>(k);
    msg.header.frame_id = o.imu_frame_id;
    SLAM_MMS_ASSIGN_OR_RETURN(
        msg.header.stamp, rosbag_internal::ToRosTime(x.stamp, "IMU sample " + std::to_string(k)));
    if (s.initial_state && k == attitude_k) {
      const Eigen::Quaterniond q(s.initial_state->T_world_body.linear());
      msg.orientation.w = q.w();
      msg.orientation.x = q.x();
      msg.orientation.y = q.y();
      msg.orientation.z = q.z();
      msg.orientation_covariance.fill(0.0);  // known orientation, unknown covariance
      if (const auto& sigma = s.initial_attitude_sigma_rpy_rad) {
        for (int i = 0; i < 3; ++i) msg.orientation_covariance[4 * i] = (*sigma)[i] * (*sigma)[i];
      }
    } else {
      msg.orientation.w = 1.0;
      msg.orientation_covariance.fill(0.0);
      msg.orientation_covariance[0] = -1.0;  // ROS: no orientation estimate
    }
    msg.linear_acceleration.x = x.accel_mps2.x();
    msg.linear_acceleration.y = x.accel_mps2.y();
    msg.linear_acceleration.z = x.accel_mps2.z();
    msg.angular_velocity.x = x.gyro_radps.x();
    msg.angular_velocity.y = x.gyro_radps.y();
    msg.angular_velocity.z = x.gyro_radps.z();
    msg.linear_acceleration_covariance.fill(0.0);
    msg.angular_velocity_covariance.fill(0.0);
    bag->write(o.imu_topic, msg.header.stamp, msg);
  }
  for (size_t k = 0; k < s.gnss.size(); ++k) {
    sensor_msgs::NavSatFix msg = rosbag_internal::ToNavSatFix(s.gnss[k], o.gnss_frame_id);
    msg.header.seq = static_cast<uint32_t>(k);
    SLAM_MMS_ASSIGN_OR_RETURN(
        msg.header.stamp,
        rosbag_internal::ToRosTime(s.gnss[k].stamp, "GNSS fix " + std::to_string(k)));
    bag->write(o.gnss_topic, msg.header.stamp, msg);
  }
  if (s.initial_state) {
    geometry_msgs::TwistStamped msg;
    msg.header.frame_id = "enu";
    SLAM_MMS_ASSIGN_OR_RETURN(msg.header.stamp,
                              rosbag_internal::ToRosTime(s.initial_state->stamp, "initial state"));
    msg.twist.linear.x = s.initial_state->v_world_mps.x();
    msg.twist.linear.y = s.initial_state->v_world_mps.y();
    msg.twist.linear.z = s.initial_state->v_world_mps.z();
    bag->write(o.velocity_topic, msg.header.stamp, msg);
  }
  return OkStatus();
}

Status WriteScans(const DriveReader& reader, const RosbagWriteOptions& o, rosbag::Bag* bag) {
  sensor_msgs::PointCloud2 msg;  // reused: its data buffer keeps its capacity
  msg.header.frame_id = o.lidar_frame_id;
  size_t skipped = 0;
  for (size_t i = 0; i < reader.NumScans(); ++i) {
    StatusOr<Scan> scan = reader.ReadScan(i);
    if (!scan.ok()) {
      if (o.skip_unreadable_scans && scan.status().code() == StatusCode::kDataLoss) {
        SLAM_MMS_LOG(kWarning) << "WriteRosbag: skipping " << scan.status().message();
        ++skipped;
        continue;
      }
      return scan.status().WithContext("WriteRosbag: " + reader.Describe());
    }
    msg.header.seq = static_cast<uint32_t>(scan->index >= 0 ? scan->index : i);
    SLAM_MMS_ASSIGN_OR_RETURN(msg.header.stamp,
                              rosbag_internal::ToRosTime(scan->stamp_start, reader.ScanSource(i)));
    rosbag_internal::EncodeCloud(scan->cloud, o.write_point_time, &msg);
    bag->write(o.lidar_topic, msg.header.stamp, msg);
  }
  if (skipped > 0) {
    SLAM_MMS_LOG(kWarning) << "WriteRosbag: skipped " << skipped << " unreadable scans";
  }
  return OkStatus();
}

}  // namespace

Status RosbagWriteOptions::Validate() const {
  SLAM_MMS_RETURN_IF_ERROR(CheckTopic("lidar_topic", lidar_topic));
  SLAM_MMS_RETURN_IF_ERROR(CheckTopic("imu_topic", imu_topic));
  SLAM_MMS_RETURN_IF_ERROR(CheckTopic("gnss_topic", gnss_topic));
  SLAM_MMS_RETURN_IF_ERROR(CheckTopic("velocity_topic", velocity_topic));
  const std::string topics[] = {lidar_topic, imu_topic, gnss_topic, velocity_topic};
  for (int a = 0; a < 4; ++a) {
    for (int b = a + 1; b < 4; ++b) {
      if (topics[a] == topics[b]) {
        return InvalidArgumentError("RosbagWriteOptions: topic " + topics[a] +
                                    " is given for two streams; each needs its own");
      }
    }
  }
  return OkStatus();
}

Status WriteRosbag(const DriveReader& reader, const std::filesystem::path& bag,
                   const RosbagWriteOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  const std::string name = bag.string();
  try {
    rosbag::Bag out;
    try {
      out.open(name, rosbag::bagmode::Write);
    } catch (const std::exception& e) {
      return UnavailableError(name + ": cannot create the ROS bag: " + e.what());
    }
    switch (options.compression) {
      case RosbagWriteOptions::Compression::kNone:
        out.setCompression(rosbag::compression::Uncompressed);
        break;
      case RosbagWriteOptions::Compression::kLz4:
        out.setCompression(rosbag::compression::LZ4);
        break;
      case RosbagWriteOptions::Compression::kBz2:
        out.setCompression(rosbag::compression::BZ2);
        break;
    }
    Status s = WriteStreams(reader.streams(), options, &out);
    if (s.ok()) s = WriteScans(reader, options, &out);
    out.close();
    if (!s.ok()) {
      std::error_code ec;
      std::filesystem::remove(bag, ec);  // no half-written bag left behind
      return s.WithContext(name);
    }
  } catch (const std::exception& e) {
    return UnavailableError(name + ": writing the ROS bag failed: " + e.what());
  } catch (...) {
    return UnavailableError(name + ": writing the ROS bag failed (unknown exception)");
  }
  return OkStatus();
}

}  // namespace slam_mms
