#include "slam_mms/rosbag/rosbag_drive_reader.hpp"

#include <geometry_msgs/TwistStamped.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/NavSatFix.h>
#include <sensor_msgs/PointCloud2.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <optional>

#include "core/option_error.hpp"
#include "rosbag/point_cloud2_codec.hpp"
#include "rosbag/ros_conversions.hpp"
#include "rosbag/rosbag_topics.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {
namespace fs = std::filesystem;
using rosbag_internal::ChooseTopic;
using rosbag_internal::StampString;
using rosbag_internal::TopicsOf;

namespace {

constexpr const char* kPointCloud2 = "sensor_msgs/PointCloud2";
constexpr const char* kImu = "sensor_msgs/Imu";
constexpr const char* kNavSatFix = "sensor_msgs/NavSatFix";
constexpr const char* kTwistStamped = "geometry_msgs/TwistStamped";
constexpr double kDefaultScanPeriod_s = 0.1;

// Strictly increasing header stamps within one stream.
// prev_number < 0: no previous message.
Status CheckIncreasing(int64_t prev_ns, int64_t ns, int64_t prev_number,
                       const std::string& source) {
  if (prev_number >= 0 && ns <= prev_ns) {
    return DataLossError(source + ": header.stamp " + StampString(ns) + " is not after message " +
                         std::to_string(prev_number) + "'s " + StampString(prev_ns) +
                         " (each stream must be strictly increasing)");
  }
  return OkStatus();
}

template <typename T>
StatusOr<boost::shared_ptr<T>> Instantiate(const rosbag::MessageInstance& m,
                                           const std::string& source) {
  boost::shared_ptr<T> msg = m.instantiate<T>();
  if (!msg) {
    return DataLossError(source + ": message is " + m.getDataType() + " (md5 " + m.getMD5Sum() +
                         "), not " + ros::message_traits::DataType<T>::value());
  }
  return msg;
}

double Median(std::vector<double> v) {
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  return v[mid];
}

}  // namespace

// ---------------------------------------------------------------------------------------------
Status RosbagDriveReader::Options::Validate() const {
  if (first_scan < 0) {
    return internal::OptionError("RosbagDriveReader::Options", "first_scan", first_scan,
                                 "must be >= 0");
  }
  if (last_scan < -1 || (last_scan >= 0 && last_scan < first_scan)) {
    return InvalidArgumentError(
        "RosbagDriveReader::Options::last_scan = " + std::to_string(last_scan) +
        "; must be -1 or >= first_scan (" + std::to_string(first_scan) + ")");
  }
  if (!(scan_period_s >= 0.0) || !std::isfinite(scan_period_s)) {
    return internal::OptionError("RosbagDriveReader::Options", "scan_period_s", scan_period_s,
                                 "must be >= 0 (0 = auto)");
  }
  if (!(stream_time_margin_s >= 0.0) || !std::isfinite(stream_time_margin_s)) {
    return internal::OptionError("RosbagDriveReader::Options", "stream_time_margin_s",
                                 stream_time_margin_s, "must be >= 0");
  }
  for (auto [name, v] :
       {std::pair<const char*, double>{"unknown_covariance_sigma_horizontal_m",
                                       unknown_covariance_sigma_horizontal_m},
        {"unknown_covariance_sigma_vertical_m", unknown_covariance_sigma_vertical_m},
        {"rtk_fixed_max_sigma_horizontal_m", rtk_fixed_max_sigma_horizontal_m}}) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      return internal::OptionError("RosbagDriveReader::Options", name, v, "must be > 0 and finite");
    }
  }
  if (!T_body_lidar.matrix().allFinite() || !T_body_lidar.linear().isUnitary(1e-6)) {
    return InvalidArgumentError(
        "RosbagDriveReader::Options::T_body_lidar: not a rigid transform (rotation not "
        "orthonormal within 1e-6 or non-finite)");
  }
  if (t_body_antenna_m && !t_body_antenna_m->allFinite()) {
    return InvalidArgumentError("RosbagDriveReader::Options::t_body_antenna_m: not finite");
  }
  return OkStatus();
}

struct RosbagDriveReader::Impl {
  struct ScanEntry {
    int64_t receipt_ns = 0;  ///< Bag receipt time, the key ReadScan looks the message up by.
    uint32_t ordinal = 0;    ///< Among the lidar messages with the same receipt time.
    int64_t header_ns = 0;
    Timestamp start, end;
    int64_t message_number = 0;
    bool has_time_field = false;
    double start_from_header_s = 0.0;
    std::string error;  ///< Non-empty: what ReadScan returns as kDataLoss.
  };
  // An IMU orientation (initial attitude candidate) and a velocity message, kept until the scan
  // range is known.
  struct Attitude {
    int64_t ns;
    Eigen::Quaterniond q_enu_body;
    std::string source;
    /// From orientation_covariance's diagonal (about the fixed x, y, z axes) where all three are
    /// > 0; ROS's all-zero "unknown" leaves it empty.
    std::optional<Eigen::Vector3d> sigma_rpy_rad;
  };
  struct Velocity {
    int64_t ns;
    Eigen::Vector3d v;
    bool enu;
    std::string source;
  };
  // One stream's message count and last stamp, for the order check.
  struct StreamState {
    uint64_t n = 0;
    int64_t prev_ns = 0;
    // Counts message `ns` of the stream after checking it comes after the previous one.
    Status Advance(int64_t ns, const std::string& source) {
      SLAM_MMS_RETURN_IF_ERROR(CheckIncreasing(prev_ns, ns, static_cast<int64_t>(n) - 1, source));
      prev_ns = ns;
      ++n;
      return OkStatus();
    }
  };

  fs::path path;
  std::string name;  ///< path as a string, for messages.
  Options options;
  mutable std::mutex bag_mutex;
  mutable rosbag::Bag bag;  // Guarded by bag_mutex (rosbag::Bag is not thread-safe).
  std::string lidar_topic, imu_topic, gnss_topic, velocity_topic;
  std::vector<ScanEntry> scans;
  DriveStreams streams;
  std::atomic<uint64_t> dropped{0};
  uint64_t skipped_gnss = 0;

  std::vector<Attitude> attitudes;
  std::vector<Velocity> velocities;
  StreamState imu_state, gnss_state, velocity_state;
  int64_t lidar_n = -1;
  int64_t prev_receipt_ns = -1;
  uint32_t ordinal = 0;
  size_t num_bad_clouds = 0;

  std::string Source(const std::string& topic, uint64_t n) const {
    return name + ": " + topic + " message " + std::to_string(n);
  }

  Status ReadStreamsAndIndex();
  Status OnImu(const rosbag::MessageInstance& m);
  Status OnGnss(const rosbag::MessageInstance& m);
  Status OnVelocity(const rosbag::MessageInstance& m);
  Status OnCloud(const rosbag::MessageInstance& m);
  void SetScanTimesWithoutTimeField();
  void KeepStreamsNearScans();
  void ChooseInitialState();
};

// One View over the four topics in receipt-time order: the bag is read once (chunks hold the
// messages of every topic).
Status RosbagDriveReader::Impl::ReadStreamsAndIndex() {
  std::vector<std::string> topics = {lidar_topic, imu_topic};
  if (!gnss_topic.empty()) topics.push_back(gnss_topic);
  if (!velocity_topic.empty()) topics.push_back(velocity_topic);
  rosbag::View view(bag, rosbag::TopicQuery(topics));
  for (const rosbag::MessageInstance& m : view) {
    const std::string& topic = m.getTopic();
    if (topic == lidar_topic) {
      SLAM_MMS_RETURN_IF_ERROR(OnCloud(m));
    } else if (topic == imu_topic) {
      SLAM_MMS_RETURN_IF_ERROR(OnImu(m));
    } else if (topic == gnss_topic) {
      SLAM_MMS_RETURN_IF_ERROR(OnGnss(m));
    } else {
      SLAM_MMS_RETURN_IF_ERROR(OnVelocity(m));
    }
  }
  if (streams.imu.empty()) {
    return InvalidArgumentError(name + ": IMU topic " + imu_topic + " has no messages");
  }
  if (scans.empty()) {
    return InvalidArgumentError(name + ": no scans on " + lidar_topic +
                                " in the range first_scan " + std::to_string(options.first_scan) +
                                " .. last_scan " + std::to_string(options.last_scan) +
                                " (the topic has " + std::to_string(lidar_n + 1) + " messages)");
  }
  SetScanTimesWithoutTimeField();
  if (num_bad_clouds > 0) {
    SLAM_MMS_LOG(kWarning) << name << ": " << num_bad_clouds << " of " << scans.size()
                           << " clouds on " << lidar_topic << " are malformed";
  }
  if (skipped_gnss > 0) {
    SLAM_MMS_LOG(kWarning) << name << ": " << gnss_topic << ": skipped " << skipped_gnss << " of "
                           << gnss_state.n << " fixes with a NaN latitude/longitude/altitude";
  }
  if (gnss_topic.empty()) {
    SLAM_MMS_LOG(kInfo) << name << ": no " << kNavSatFix << " topic: no GNSS";
  }
  KeepStreamsNearScans();
  ChooseInitialState();
  return OkStatus();
}

Status RosbagDriveReader::Impl::OnImu(const rosbag::MessageInstance& m) {
  const std::string source = Source(imu_topic, imu_state.n);
  SLAM_MMS_ASSIGN_OR_RETURN(const auto msg, Instantiate<sensor_msgs::Imu>(m, source));
  const auto ns = static_cast<int64_t>(msg->header.stamp.toNSec());
  SLAM_MMS_RETURN_IF_ERROR(imu_state.Advance(ns, source));
  ImuSample s;
  s.stamp = Timestamp::FromNanoseconds(ns);
  s.accel_mps2 = Eigen::Vector3d(msg->linear_acceleration.x, msg->linear_acceleration.y,
                                 msg->linear_acceleration.z);
  s.gyro_radps =
      Eigen::Vector3d(msg->angular_velocity.x, msg->angular_velocity.y, msg->angular_velocity.z);
  if (!s.accel_mps2.allFinite() || !s.gyro_radps.allFinite()) {
    return DataLossError(source + ": non-finite linear_acceleration or angular_velocity");
  }
  if (msg->orientation_covariance[0] >= 0.0) {
    const Eigen::Quaterniond q(msg->orientation.w, msg->orientation.x, msg->orientation.y,
                               msg->orientation.z);
    if (q.coeffs().allFinite() && std::abs(q.norm() - 1.0) < 1e-3) {
      const Eigen::Vector3d var(msg->orientation_covariance[0], msg->orientation_covariance[4],
                                msg->orientation_covariance[8]);
      std::optional<Eigen::Vector3d> sigma;
      if (var.allFinite() && var.minCoeff() > 0.0) sigma = var.cwiseSqrt();
      attitudes.push_back({ns, q.normalized(), source, sigma});
    }
  }
  streams.imu.push_back(s);
  streams.imu_source.push_back(source);
  return OkStatus();
}

Status RosbagDriveReader::Impl::OnVelocity(const rosbag::MessageInstance& m) {
  const std::string source = Source(velocity_topic, velocity_state.n);
  SLAM_MMS_ASSIGN_OR_RETURN(const auto msg, Instantiate<geometry_msgs::TwistStamped>(m, source));
  const auto ns = static_cast<int64_t>(msg->header.stamp.toNSec());
  SLAM_MMS_RETURN_IF_ERROR(velocity_state.Advance(ns, source));
  const Eigen::Vector3d v(msg->twist.linear.x, msg->twist.linear.y, msg->twist.linear.z);
  if (v.allFinite()) {
    velocities.push_back({ns, v, rosbag_internal::IsEnuFrameId(msg->header.frame_id),
                          source + " (frame_id '" + msg->header.frame_id + "')"});
  }
  return OkStatus();
}

Status RosbagDriveReader::Impl::OnGnss(const rosbag::MessageInstance& m) {
  const std::string source = Source(gnss_topic, gnss_state.n);
  SLAM_MMS_ASSIGN_OR_RETURN(const auto msg, Instantiate<sensor_msgs::NavSatFix>(m, source));
  const auto ns = static_cast<int64_t>(msg->header.stamp.toNSec());
  SLAM_MMS_RETURN_IF_ERROR(gnss_state.Advance(ns, source));
  if (!std::isfinite(msg->latitude) || !std::isfinite(msg->longitude) ||
      !std::isfinite(msg->altitude)) {
    ++skipped_gnss;
    return OkStatus();
  }
  GnssFix fix;
  fix.stamp = Timestamp::FromNanoseconds(ns);
  fix.latitude_deg = msg->latitude;
  fix.longitude_deg = msg->longitude;
  fix.height_m = msg->altitude;
  rosbag_internal::NavSatFixSigmas(*msg, options.unknown_covariance_sigma_horizontal_m,
                                   options.unknown_covariance_sigma_vertical_m,
                                   &fix.sigma_horizontal_m, &fix.sigma_vertical_m);
  fix.type = RosbagFixType(msg->status.status, fix.sigma_horizontal_m,
                           options.rtk_fixed_max_sigma_horizontal_m);
  fix.num_satellites = 0;
  streams.gnss.push_back(fix);
  streams.gnss_source.push_back(source);
  return OkStatus();
}

Status RosbagDriveReader::Impl::OnCloud(const rosbag::MessageInstance& m) {
  const int64_t n = ++lidar_n;
  const auto receipt_ns = static_cast<int64_t>(m.getTime().toNSec());
  ordinal = receipt_ns == prev_receipt_ns ? ordinal + 1 : 0;
  prev_receipt_ns = receipt_ns;
  if (n < options.first_scan || (options.last_scan >= 0 && n > options.last_scan)) {
    return OkStatus();  // not deserialised
  }
  const std::string source = Source(lidar_topic, static_cast<uint64_t>(n));
  // One cloud at a time: read, take its stamps, drop it.
  SLAM_MMS_ASSIGN_OR_RETURN(const auto msg, Instantiate<sensor_msgs::PointCloud2>(m, source));
  ScanEntry e;
  e.receipt_ns = receipt_ns;
  e.ordinal = ordinal;
  e.message_number = n;
  e.header_ns = static_cast<int64_t>(msg->header.stamp.toNSec());
  SLAM_MMS_RETURN_IF_ERROR(CheckIncreasing(scans.empty() ? 0 : scans.back().header_ns, e.header_ns,
                                           scans.empty() ? -1 : scans.back().message_number,
                                           source));
  SLAM_MMS_ASSIGN_OR_RETURN(const rosbag_internal::CloudLayout layout,
                            rosbag_internal::ParseCloudLayout(*msg, source));
  e.has_time_field = layout.time.present();
  Status size_ok = rosbag_internal::CheckCloudSize(*msg, source);
  if (size_ok.ok() && e.has_time_field) {
    auto range = rosbag_internal::ComputeCloudTimeRange(*msg, layout, options.time_field, source);
    if (range.ok()) {
      const double min0 = std::min(0.0, range->min_s);
      const auto start_offset_ns = static_cast<int64_t>(std::llround(min0 * 1e9));
      e.start = Timestamp::FromNanoseconds(e.header_ns + start_offset_ns);
      e.end = Timestamp::FromNanoseconds(
          std::max(e.start.nanoseconds(),
                   e.header_ns + static_cast<int64_t>(std::llround(range->max_s * 1e9))));
      e.start_from_header_s = static_cast<double>(start_offset_ns) * 1e-9;
    } else {
      size_ok = range.status();
    }
  }
  if (!size_ok.ok()) {
    e.error = size_ok.message();
    ++num_bad_clouds;
    SLAM_MMS_LOG(kWarning) << e.error << " (ReadScan will return kDataLoss)";
  }
  scans.push_back(std::move(e));
  return OkStatus();
}

// Clouds without a time field (or unreadable ones): [header, header + period] or
// [header - period, header].
void RosbagDriveReader::Impl::SetScanTimesWithoutTimeField() {
  double period_s = options.scan_period_s;
  if (period_s <= 0.0) {
    std::vector<double> gaps;
    for (size_t i = 1; i < scans.size(); ++i) {
      gaps.push_back(static_cast<double>(scans[i].header_ns - scans[i - 1].header_ns) * 1e-9);
    }
    period_s = gaps.empty() ? kDefaultScanPeriod_s : Median(gaps);
    if (gaps.empty()) {
      SLAM_MMS_LOG(kInfo) << name << ": one scan: scan period " << period_s << " s assumed";
    }
  }
  const auto period_ns = static_cast<int64_t>(std::llround(period_s * 1e9));
  for (ScanEntry& e : scans) {
    if (e.has_time_field && e.error.empty()) continue;
    if (options.header_stamp == HeaderStamp::kScanStart) {
      e.start = Timestamp::FromNanoseconds(e.header_ns);
      e.end = Timestamp::FromNanoseconds(e.header_ns + period_ns);
    } else {
      e.start = Timestamp::FromNanoseconds(e.header_ns - period_ns);
      e.end = Timestamp::FromNanoseconds(e.header_ns);
    }
  }
}

// With a scan range: the streams within [first start - margin, last end + margin], as
// KittiRawReader does.
void RosbagDriveReader::Impl::KeepStreamsNearScans() {
  if (options.first_scan == 0 && options.last_scan < 0) return;
  Timestamp lo = scans.front().start, hi = scans.front().end;
  for (const ScanEntry& e : scans) {
    lo = std::min(lo, e.start);
    hi = std::max(hi, e.end);
  }
  lo = lo.PlusSeconds(-options.stream_time_margin_s);
  hi = hi.PlusSeconds(options.stream_time_margin_s);
  const auto keep = [&](auto* records, std::vector<std::string>* sources) {
    size_t k = 0;
    for (size_t i = 0; i < records->size(); ++i) {
      const Timestamp t = (*records)[i].stamp;
      if (t < lo || t > hi) continue;
      (*records)[k] = (*records)[i];
      (*sources)[k] = std::move((*sources)[i]);
      ++k;
    }
    records->resize(k);
    sources->resize(k);
  };
  keep(&streams.imu, &streams.imu_source);
  keep(&streams.gnss, &streams.gnss_source);
  if (streams.imu.empty()) {
    SLAM_MMS_LOG(kWarning) << name << ": no IMU sample within " << options.stream_time_margin_s
                           << " s of the selected scans";
  }
}

// The attitude: the last orientation at or before the first scan's start, else the first after
// it; the velocity: the message nearest to that attitude.
void RosbagDriveReader::Impl::ChooseInitialState() {
  if (attitudes.empty()) {
    SLAM_MMS_LOG(kInfo) << name << ": no IMU message on " << imu_topic
                        << " carries an orientation: the filter aligns itself";
    if (!velocities.empty()) {
      SLAM_MMS_LOG(kInfo) << name << ": " << velocity_topic
                          << " ignored: no IMU orientation to start from";
    }
    return;
  }
  const int64_t first_scan_ns = scans.front().start.nanoseconds();
  const Attitude* a = &attitudes.front();
  for (const Attitude& c : attitudes) {
    if (c.ns > first_scan_ns) break;
    a = &c;
  }
  InsState state;
  state.stamp = Timestamp::FromNanoseconds(a->ns);
  state.T_world_body.linear() = a->q_enu_body.toRotationMatrix();
  streams.initial_state_source = a->source;
  streams.initial_attitude_sigma_rpy_rad = a->sigma_rpy_rad;
  const Velocity* best = nullptr;
  for (const Velocity& v : velocities) {
    if (best == nullptr || std::abs(v.ns - a->ns) < std::abs(best->ns - a->ns)) best = &v;
  }
  if (best != nullptr) {
    state.v_world_mps =
        best->enu ? best->v : Eigen::Vector3d(state.T_world_body.linear() * best->v);
    streams.initial_state_source += "; velocity " + best->source;
    if (std::abs(best->ns - a->ns) > 100000000) {
      SLAM_MMS_LOG(kWarning) << name << ": the initial velocity (" << best->source << ") is "
                             << std::abs(best->ns - a->ns) * 1e-9 << " s from the initial attitude";
    }
  }
  streams.initial_state = state;
  attitudes.clear();
  attitudes.shrink_to_fit();
  velocities.clear();
  velocities.shrink_to_fit();
}

// ---------------------------------------------------------------------------------------------
StatusOr<std::unique_ptr<RosbagDriveReader>> RosbagDriveReader::Open(const fs::path& bag,
                                                                     const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  std::error_code ec;
  if (!fs::is_regular_file(bag, ec)) {
    return NotFoundError(bag.string() + ": no such ROS bag file");
  }
  auto impl = std::make_unique<Impl>();
  impl->path = bag;
  impl->name = bag.string();
  impl->options = options;
  try {
    impl->bag.open(bag.string(), rosbag::bagmode::Read);
    const std::vector<RosbagTopic> topics = TopicsOf(impl->bag);
    SLAM_MMS_ASSIGN_OR_RETURN(impl->lidar_topic,
                              ChooseTopic(topics, options.lidar_topic, kPointCloud2, "lidar_topic",
                                          /*required=*/true, impl->name));
    SLAM_MMS_ASSIGN_OR_RETURN(impl->imu_topic, ChooseTopic(topics, options.imu_topic, kImu,
                                                           "imu_topic", true, impl->name));
    SLAM_MMS_ASSIGN_OR_RETURN(impl->gnss_topic, ChooseTopic(topics, options.gnss_topic, kNavSatFix,
                                                            "gnss_topic", false, impl->name));
    SLAM_MMS_ASSIGN_OR_RETURN(impl->velocity_topic,
                              ChooseTopic(topics, options.velocity_topic, kTwistStamped,
                                          "velocity_topic", false, impl->name));
    SLAM_MMS_RETURN_IF_ERROR(impl->ReadStreamsAndIndex());
  } catch (const rosbag::BagUnindexedException& e) {
    return DataLossError(impl->name +
                         ": unindexed ROS bag (`rosbag reindex` repairs it): " + e.what());
  } catch (const std::exception& e) {
    return DataLossError(impl->name + ": corrupt or truncated ROS bag: " + e.what());
  } catch (...) {
    return DataLossError(impl->name + ": corrupt or truncated ROS bag (unknown exception)");
  }
  impl->streams.T_body_lidar = options.T_body_lidar;
  impl->streams.t_body_antenna_m = options.t_body_antenna_m;
  impl->streams.imu_frame_is_vehicle_frame = options.imu_frame_is_vehicle_frame;
  SLAM_MMS_LOG(kInfo) << impl->name << ": " << impl->scans.size() << " scans on "
                      << impl->lidar_topic << ", " << impl->streams.imu.size() << " IMU samples on "
                      << impl->imu_topic << ", " << impl->streams.gnss.size() << " GNSS fixes"
                      << (impl->gnss_topic.empty() ? std::string() : " on " + impl->gnss_topic);
  return std::unique_ptr<RosbagDriveReader>(new RosbagDriveReader(std::move(impl)));
}

StatusOr<std::vector<RosbagTopic>> RosbagDriveReader::ListTopics(const fs::path& bag) {
  std::error_code ec;
  if (!fs::is_regular_file(bag, ec)) return NotFoundError(bag.string() + ": no such ROS bag file");
  try {
    rosbag::Bag b(bag.string(), rosbag::bagmode::Read);
    return TopicsOf(b);
  } catch (const std::exception& e) {
    return DataLossError(bag.string() + ": corrupt or truncated ROS bag: " + e.what());
  } catch (...) {
    return DataLossError(bag.string() + ": corrupt or truncated ROS bag (unknown exception)");
  }
}

RosbagDriveReader::RosbagDriveReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RosbagDriveReader::~RosbagDriveReader() = default;

std::string RosbagDriveReader::Describe() const { return "ROS 1 bag " + impl_->name; }
size_t RosbagDriveReader::NumScans() const { return impl_->scans.size(); }
Timestamp RosbagDriveReader::ScanStart(size_t i) const { return impl_->scans.at(i).start; }
Timestamp RosbagDriveReader::ScanEnd(size_t i) const { return impl_->scans.at(i).end; }
std::string RosbagDriveReader::ScanSource(size_t i) const {
  return impl_->Source(impl_->lidar_topic,
                       static_cast<uint64_t>(impl_->scans.at(i).message_number));
}
const DriveStreams& RosbagDriveReader::streams() const { return impl_->streams; }
uint64_t RosbagDriveReader::TotalDroppedPoints() const { return impl_->dropped.load(); }
const RosbagDriveReader::Options& RosbagDriveReader::options() const { return impl_->options; }
const fs::path& RosbagDriveReader::bag_path() const { return impl_->path; }
const std::string& RosbagDriveReader::lidar_topic() const { return impl_->lidar_topic; }
const std::string& RosbagDriveReader::imu_topic() const { return impl_->imu_topic; }
const std::string& RosbagDriveReader::gnss_topic() const { return impl_->gnss_topic; }
const std::string& RosbagDriveReader::velocity_topic() const { return impl_->velocity_topic; }
bool RosbagDriveReader::ScanHasTimeField(size_t i) const {
  return impl_->scans.at(i).has_time_field;
}
uint64_t RosbagDriveReader::NumSkippedGnssFixes() const { return impl_->skipped_gnss; }

StatusOr<Scan> RosbagDriveReader::ReadScan(size_t i) const {
  if (i >= impl_->scans.size()) {
    return OutOfRangeError("RosbagDriveReader::ReadScan(" + std::to_string(i) + "): only " +
                           std::to_string(impl_->scans.size()) + " scans");
  }
  const Impl::ScanEntry& e = impl_->scans[i];
  const std::string source = ScanSource(i);
  if (!e.error.empty()) return DataLossError(e.error);
  boost::shared_ptr<sensor_msgs::PointCloud2> msg;
  try {
    // Only message i: the lidar topic at its receipt time.
    const std::lock_guard<std::mutex> lock(impl_->bag_mutex);
    ros::Time t;
    t.fromNSec(static_cast<uint64_t>(e.receipt_ns));
    rosbag::View view(impl_->bag, rosbag::TopicQuery(impl_->lidar_topic), t, t);
    // Message `ordinal` among those at t, as in Open's pass; should the order of equal receipt
    // times differ (several connections on the topic), the one with the indexed header stamp.
    std::vector<rosbag::MessageInstance> at_t;
    for (const rosbag::MessageInstance& m : view) {
      if (m.getTime() == t) at_t.push_back(m);
    }
    const auto matches = [&](const boost::shared_ptr<sensor_msgs::PointCloud2>& c) {
      return c && static_cast<int64_t>(c->header.stamp.toNSec()) == e.header_ns;
    };
    if (e.ordinal < at_t.size()) msg = at_t[e.ordinal].instantiate<sensor_msgs::PointCloud2>();
    for (size_t k = 0; k < at_t.size() && !matches(msg); ++k) {
      if (k != e.ordinal) msg = at_t[k].instantiate<sensor_msgs::PointCloud2>();
    }
  } catch (const std::exception& ex) {
    return DataLossError(source + ": reading the message failed: " + ex.what());
  } catch (...) {
    return DataLossError(source + ": reading the message failed (unknown exception)");
  }
  if (!msg || static_cast<int64_t>(msg->header.stamp.toNSec()) != e.header_ns) {
    return DataLossError(source + ": not found again at receipt time " + StampString(e.receipt_ns) +
                         " (the bag changed since Open?)");
  }
  // Decoding needs no bag: outside the lock.
  SLAM_MMS_ASSIGN_OR_RETURN(const rosbag_internal::CloudLayout layout,
                            rosbag_internal::ParseCloudLayout(*msg, source));
  SLAM_MMS_RETURN_IF_ERROR(rosbag_internal::CheckCloudSize(*msg, source));
  const size_t n = static_cast<size_t>(msg->width) * msg->height;
  if (n == 0) return DataLossError(source + ": cloud contains no points");
  rosbag_internal::DecodeParams params;
  params.time_field = impl_->options.time_field;
  params.start_from_header_s = e.start_from_header_s;
  params.duration_s = e.end.SecondsSince(e.start);
  params.spin = impl_->options.spin;
  params.per_point_time = impl_->options.per_point_time;
  Scan scan;
  scan.index = e.message_number;
  scan.stamp_start = e.start;
  scan.stamp_end = e.end;
  scan.stamp_trigger = Timestamp::FromNanoseconds(e.header_ns);
  scan.source = source;
  const size_t dropped = rosbag_internal::DecodeCloud(*msg, layout, params, &scan.cloud);
  if (dropped > 0) {
    impl_->dropped += dropped;
    SLAM_MMS_LOG(kWarning) << source << ": dropped " << dropped << " of " << n
                           << " points with NaN/Inf values";
  }
  if (scan.cloud.empty()) {
    return DataLossError(source + ": cloud has no finite point (" + std::to_string(n) +
                         " points, all NaN/Inf)");
  }
  return scan;
}

}  // namespace slam_mms
