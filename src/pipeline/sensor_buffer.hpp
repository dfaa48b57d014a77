#pragma once
// SensorBuffer: MappingSystem's input stage (issue #19, part 2). It holds what arrives before it
// can be used, in the order the rest of the system needs it:
//  - the per-stream time order of IMU samples and GNSS fixes (an older record is rejected, naming
//    the stream and both times);
//  - IMU and GNSS records that arrive before the first scan (the GNSS outage windows are relative
//    to the first scan's start, so no fix can be judged before it), replayed merged in time order;
//  - the IMU history that F_Prein and the POS-start correction read (a few seconds back);
//  - the scans waiting for the POS to cover their end time, and the admission of a scan (empty,
//    no finite point, stamps reversed, not after the previous scan: skipped with the reason).
//
// Ownership: owns copies of the records. Thread safety: not thread-safe (MappingSystem's thread).

#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms::internal {

class SensorBuffer {
 public:
  /// IMU samples kept behind the oldest scan still to come (TrimImuHistory) [s].
  static constexpr double kImuHistoryS = 5.0;
  /// ImuBetween's margin on both sides of the window [s]: preintegration needs the samples that
  /// bracket the window's ends.
  static constexpr double kImuWindowMarginS = 0.2;

  /// Time order per stream: InvalidArgument "MappingSystem: IMU sample at T is older than the
  /// previous one at T0 (data must come in time order)" (nothing is changed then).
  [[nodiscard]] Status AcceptImuTime(Timestamp t);
  [[nodiscard]] Status AcceptGnssTime(Timestamp t);

  /// Before the first scan: holds the record.
  void HoldImu(const ImuSample& sample) { held_imu_.push_back(sample); }
  void HoldGnss(const GnssFix& fix) { held_gnss_.push_back(fix); }
  /// Replays the held records merged in time order (an IMU sample before a fix of the same
  /// stamp), then forgets them. Stops at the first error.
  [[nodiscard]] Status ReleaseHeld(const std::function<Status(const ImuSample&)>& imu,
                                   const std::function<Status(const GnssFix&)>& gnss);

  /// The IMU history (every sample fed to the system after the first scan's arrival).
  void RecordImu(const ImuSample& sample) { imu_history_.push_back(sample); }
  const std::deque<ImuSample>& imu_history() const { return imu_history_; }
  /// The recorded samples stamped within [from - margin, to + margin], in order.
  std::vector<ImuSample> ImuBetween(Timestamp from, Timestamp to) const;
  /// Forgets the samples more than kImuHistoryS older than the oldest queued scan's start (or,
  /// with no scan queued, than `last_processed_start`).
  void TrimImuHistory(Timestamp last_processed_start);

  /// The newest time the POS has data for (IMU, GNSS or external pose).
  void MarkPosInput(Timestamp t);
  bool has_pos_input() const { return have_pos_input_; }
  Timestamp last_pos_input() const { return last_pos_input_; }
  /// The POS covers the scan's end.
  bool PosCovers(const Scan& scan) const {
    return have_pos_input_ && scan.stamp_end <= last_pos_input_;
  }

  /// Why the scan cannot be queued (empty, no finite point, stamp_end before stamp_start, not
  /// after the newest queued or processed scan `last_processed_start`, when `have_processed`);
  /// empty when it can.
  std::optional<std::string> ScanRejection(const Scan& scan, bool have_processed,
                                           Timestamp last_processed_start) const;
  std::deque<Scan>& scans() { return scans_; }
  const std::deque<Scan>& scans() const { return scans_; }

 private:
  bool have_imu_ = false;
  bool have_gnss_ = false;
  Timestamp last_imu_;
  Timestamp last_gnss_;
  std::vector<ImuSample> held_imu_;
  std::vector<GnssFix> held_gnss_;
  std::deque<ImuSample> imu_history_;
  bool have_pos_input_ = false;
  Timestamp last_pos_input_;
  std::deque<Scan> scans_;
};

}  // namespace slam_mms::internal
