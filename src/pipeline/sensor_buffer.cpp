#include "pipeline/sensor_buffer.hpp"

#include <algorithm>

namespace slam_mms::internal {
namespace {

Status Accept(const char* stream, Timestamp t, Timestamp* last, bool* have) {
  if (*have && t < *last) {
    return InvalidArgumentError(std::string("MappingSystem: ") + stream + " at " +
                                t.ToKittiString() + " is older than the previous one at " +
                                last->ToKittiString() + " (data must come in time order)");
  }
  *last = t;
  *have = true;
  return OkStatus();
}

}  // namespace

Status SensorBuffer::AcceptImuTime(Timestamp t) {
  return Accept("IMU sample", t, &last_imu_, &have_imu_);
}

Status SensorBuffer::AcceptGnssTime(Timestamp t) {
  return Accept("GNSS fix", t, &last_gnss_, &have_gnss_);
}

Status SensorBuffer::ReleaseHeld(const std::function<Status(const ImuSample&)>& imu,
                                 const std::function<Status(const GnssFix&)>& gnss) {
  size_t i = 0, j = 0;
  while (i < held_imu_.size() || j < held_gnss_.size()) {
    const bool take_imu = j >= held_gnss_.size() ||
                          (i < held_imu_.size() && held_imu_[i].stamp <= held_gnss_[j].stamp);
    if (take_imu) {
      SLAM_MMS_RETURN_IF_ERROR(imu(held_imu_[i++]));
    } else {
      SLAM_MMS_RETURN_IF_ERROR(gnss(held_gnss_[j++]));
    }
  }
  held_imu_.clear();
  held_gnss_.clear();
  return OkStatus();
}

std::vector<ImuSample> SensorBuffer::ImuBetween(Timestamp from, Timestamp to) const {
  std::vector<ImuSample> out;
  for (const ImuSample& s : imu_history_) {
    if (s.stamp.SecondsSince(from) >= -kImuWindowMarginS &&
        to.SecondsSince(s.stamp) >= -kImuWindowMarginS) {
      out.push_back(s);
    }
  }
  return out;
}

void SensorBuffer::TrimImuHistory(Timestamp last_processed_start) {
  const Timestamp keep_from = scans_.empty() ? last_processed_start : scans_.front().stamp_start;
  while (!imu_history_.empty() &&
         keep_from.SecondsSince(imu_history_.front().stamp) > kImuHistoryS) {
    imu_history_.pop_front();
  }
}

void SensorBuffer::MarkPosInput(Timestamp t) {
  if (!have_pos_input_ || last_pos_input_ < t) last_pos_input_ = t;
  have_pos_input_ = true;
}

std::optional<std::string> SensorBuffer::ScanRejection(const Scan& scan, bool have_processed,
                                                       Timestamp last_processed_start) const {
  if (scan.cloud.empty()) return std::string("no points");
  const auto& points = scan.cloud.points();
  if (std::none_of(points.begin(), points.end(),
                   [](const Eigen::Vector3f& p) { return p.allFinite(); })) {
    return std::string("no finite point");
  }
  if (!(scan.stamp_start <= scan.stamp_end)) return std::string("stamp_end before stamp_start");
  const Timestamp newest = scans_.empty() ? (have_processed ? last_processed_start : Timestamp())
                                          : scans_.back().stamp_start;
  if ((have_processed || !scans_.empty()) && !(newest < scan.stamp_start)) {
    return "it starts at " + scan.stamp_start.ToKittiString() +
           ", not after the previous scan at " + newest.ToKittiString();
  }
  return std::nullopt;
}

}  // namespace slam_mms::internal
