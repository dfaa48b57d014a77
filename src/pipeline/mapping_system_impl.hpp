#pragma once
// MappingSystem::Impl: the facade's state, shared by its files:
//   mapping_system.cpp          options, Create, the input API, Finish, small getters
//   mapping_system_input.cpp    the sensor buffer: IMU/GNSS into the POS, time order, the queue
//   mapping_system_scans.cpp    per scan: the motion input for level 1 from the POS (F_Odom or
//                               F_Prein), the POS-only mapper (gnss_ins), the submaps to level 2
//   mapping_system_outputs.cpp  the final trajectory and map
// Private to the pipeline module.

#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "pipeline/motion_input_builder.hpp"
#include "pipeline/pos_mapper.hpp"
#include "pipeline/scan_deskewer.hpp"
#include "pipeline/sensor_buffer.hpp"
#include "pipeline/submap_manager.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"

namespace slam_mms {

struct MappingSystem::Impl {
  Options opt;
  InsFilter ins;
  std::unique_ptr<Localizer> loc;
  std::unique_ptr<SubmapManager> level2;

  bool external_pos = false;
  bool have_first_scan = false;
  bool finished = false;
  /// Time order, the records held before the first scan, the IMU history and the scan queue.
  internal::SensorBuffer input;
  Timestamp last_scan_start;  // of the last processed scan
  bool have_scan = false;

  std::vector<LocalizationResult> results;
  std::function<void(const LocalizationResult&)> callback;
  int skipped = 0;
  internal::MotionInputBuilder motion_builder;  // level 1's motion input (F_Odom/F_Prein/CV)
  bool in_outage = false;
  Timestamp outage_start;
  bool gnss_returned_pending = false;
  bool have_gnss_fed = false;  // GNSS fixes reached the GnssPrior (also with an external POS)
  size_t submaps_reported = 0;
  /// Level2Options::pos_attitude_cross_covariance: per submap, the scan stamp at which the POS
  /// filter's attitude epoch was marked (the first scan where GNSS holds the POS, as
  /// ReportFinishedSubmaps picks it) and the chain from the previous submap's epoch.
  struct PosEpoch {
    Timestamp stamp;
    std::optional<SubmapManager::PosAttitude::Link> link;
  };
  std::map<int32_t, PosEpoch> pos_epochs;  // of the submaps not reported yet
  int32_t pos_epoch_submap = -1;           // the submap of the filter's current epoch
  /// The last submap given a POS attitude, where that was taken at its epoch's scan; else -1.
  int32_t last_attitude_at_epoch = -1;
  /// Marks the POS's attitude epoch at the first scan of a submap where GNSS holds it.
  void MarkPosEpoch(const Scan& scan, const LocalizationResult& res);

  // gnss_ins mode.
  internal::PosMapper pos_mapper;

  // ---- the sensor buffer (mapping_system_input.cpp) --------------------------------------------
  Status FeedImu(const ImuSample& s);
  Status FeedGnss(const GnssFix& fix);
  /// With an external POS the fixes are not fused: each is decided (GnssPrior: outage windows,
  /// type, innovation against the POS antenna position at the fix time) for level 2 only.
  StatusOr<GnssDecisionResult> DecideAgainstExternalPos(const GnssFix& fix);
  /// Replays the data buffered before the first scan, merged in time order.
  Status FlushPending();
  bool Ready(const Scan& scan) const;

  // ---- per scan and level 2 (mapping_system_scans.cpp) -----------------------------------------
  Status ProcessQueued();
  /// POS states kept before the oldest time still to be asked for [s].
  static constexpr double kPosStatesKeptS = 30.0;
  /// Lets the POS forget the states no query needs any more (ForgetStatesBefore): its history
  /// then follows the submaps, not InsFilter::Options::history_s (600 s by default: 29 MB at
  /// 100 Hz, growing over a drive's first ten minutes).
  void ForgetOldPosStates();
  /// One scan, once the POS covers it: POS-only mapping (gnss_ins) or level 1 and 2.
  Status ProcessScan(const Scan& scan);
  /// The POS at the scan's start and end (the start taken back from the end where the POS starts
  /// inside the scan).
  std::pair<StatusOr<InsState>, StatusOr<InsState>> PosOverScan(const Scan& scan) const;
  /// gnss_ins: the scan de-skewed and placed with the POS; false when skipped (no POS state).
  StatusOr<bool> MapWithPos(const Scan& scan, const StatusOr<InsState>& s0,
                            const StatusOr<InsState>& s1, LocalizationResult* res);
  /// Level 1's motion input: F_Odom from the POS while GNSS is valid and the POS did not jump,
  /// else IMU preintegration (constant velocity without IMU); constant velocity in lidar_only.
  /// Updates the outage state (level 2's GNSS-return trigger).
  ScanMotionInput MotionInput(const Scan& scan, const StatusOr<InsState>& s0,
                              const StatusOr<InsState>& s1);
  /// Level 1 on the scan, then the submaps it finished to level 2; false when the scan was
  /// skipped as bad input.
  StatusOr<bool> Localize(const Scan& scan, const ScanMotionInput& motion, LocalizationResult* res);
  void UpdateOutageState(bool gnss_valid, Timestamp t);
  /// Hands the submaps level 1 has finished to level 2, in order.
  Status ReportFinishedSubmaps();
  /// The one way level 2 reaches level 1: its estimates, applied to the submaps (and their
  /// surfels) in order.
  Status ApplyLevel2(const std::vector<SubmapPoseUpdate>& updates);
};

}  // namespace slam_mms
