// WriteKittiRawDrive (kitti_drive_reader.hpp): any DriveReader back to a KITTI raw sync folder.
#include <algorithm>
#include <cmath>
#include <vector>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/io/kitti_raw_writer.hpp"

namespace slam_mms {
namespace {

// NCOM navstat/posmode for a fix type (inverse of OxtsFixType).
void SetFixType(GnssFixType type, OxtsRecord* r) {
  r->navstat = type == GnssFixType::kNone ? 0 : kOxtsNavstatLocked;
  switch (type) {
    case GnssFixType::kNone: r->posmode = static_cast<int>(OxtsGnssMode::kNone); break;
    case GnssFixType::kSingle: r->posmode = static_cast<int>(OxtsGnssMode::kSps); break;
    case GnssFixType::kDifferential:
      r->posmode = static_cast<int>(OxtsGnssMode::kDifferential);
      break;
    case GnssFixType::kRtkFloat: r->posmode = static_cast<int>(OxtsGnssMode::kRtkFloat); break;
    case GnssFixType::kRtkFixed: r->posmode = static_cast<int>(OxtsGnssMode::kRtkInteger); break;
  }
}

// Attitude (and ENU velocity) at `t`: the external POS record at or before t, else the initial
// state at the first record only.
bool AttitudeAt(const DriveStreams& s, Timestamp t, bool first, OxtsRecord* r) {
  if (!s.pos.empty()) {
    auto it = std::upper_bound(s.pos.begin(), s.pos.end(), t,
                               [](Timestamp a, const PosRecord& p) { return a < p.stamp; });
    const PosRecord& p = it == s.pos.begin() ? s.pos.front() : *std::prev(it);
    SetOxtsAttitude(p.R_enu_body, r);
    return true;
  }
  if (first && s.initial_state) {
    SetOxtsAttitude(s.initial_state->T_world_body.linear(), r);
    r->ve = s.initial_state->v_world_mps.x();
    r->vn = s.initial_state->v_world_mps.y();
    r->vu = s.initial_state->v_world_mps.z();
    return true;
  }
  return false;
}

}  // namespace

Status WriteKittiRawDrive(const DriveReader& reader, const std::filesystem::path& drive_dir,
                          size_t* fixes_dropped) {
  const DriveStreams& s = reader.streams();
  if (s.t_body_antenna_m && !s.t_body_antenna_m->isZero()) {
    SLAM_MMS_LOG(kWarning) << drive_dir.string()
                           << ": KITTI raw has no GNSS lever arm; t_body_antenna_m not written";
  }
  SLAM_MMS_ASSIGN_OR_RETURN(KittiRawWriter writer, KittiRawWriter::Create(drive_dir));
  SLAM_MMS_RETURN_IF_ERROR(writer.WriteCalibration(s.T_body_lidar.inverse()));

  // IMU: every sample as a 100 Hz record (the first one carries the initial attitude).
  for (size_t i = 0; i < s.imu.size(); ++i) {
    OxtsRecord r;
    r.ax = s.imu[i].accel_mps2.x();
    r.ay = s.imu[i].accel_mps2.y();
    r.az = s.imu[i].accel_mps2.z();
    r.wx = s.imu[i].gyro_radps.x();
    r.wy = s.imu[i].gyro_radps.y();
    r.wz = s.imu[i].gyro_radps.z();
    AttitudeAt(s, s.imu[i].stamp, i == 0, &r);
    SLAM_MMS_RETURN_IF_ERROR(writer.AddImuOxts(s.imu[i].stamp, r).WithContext(s.imu_source[i]));
  }

  // Scans, each with one OXTS record: the nearest unused fix to its trigger time.
  size_t next_fix = 0, used = 0;
  Timestamp last_stamp = Timestamp::FromNanoseconds(INT64_MIN);
  for (size_t i = 0; i < reader.NumScans(); ++i) {
    SLAM_MMS_ASSIGN_OR_RETURN(Scan scan, reader.ReadScan(i));
    scan.stamp_trigger = Timestamp::FromNanoseconds(
        scan.stamp_start.nanoseconds() +
        (scan.stamp_end.nanoseconds() - scan.stamp_start.nanoseconds()) / 2);
    // Candidates after the previous record; take the nearest to the trigger.
    while (next_fix < s.gnss.size() && s.gnss[next_fix].stamp <= last_stamp) ++next_fix;
    size_t best = s.gnss.size();
    for (size_t k = next_fix; k < s.gnss.size(); ++k) {
      if (best < s.gnss.size() &&
          std::llabs(s.gnss[k].stamp.nanoseconds() - scan.stamp_trigger.nanoseconds()) >=
              std::llabs(s.gnss[best].stamp.nanoseconds() - scan.stamp_trigger.nanoseconds())) {
        break;
      }
      best = k;
    }
    // A fix belongs to this scan only when it is nearer to it than to the next scan.
    if (best < s.gnss.size() && i + 1 < reader.NumScans()) {
      const int64_t t_next =
          (reader.ScanStart(i + 1).nanoseconds() + reader.ScanEnd(i + 1).nanoseconds()) / 2;
      const int64_t t_fix = s.gnss[best].stamp.nanoseconds();
      if (std::llabs(t_fix - t_next) < std::llabs(t_fix - scan.stamp_trigger.nanoseconds())) {
        best = s.gnss.size();
      }
    }
    OxtsRecord r;
    Timestamp stamp = scan.stamp_trigger;
    if (best < s.gnss.size()) {
      const GnssFix& f = s.gnss[best];
      r.lat_deg = f.latitude_deg;
      r.lon_deg = f.longitude_deg;
      r.alt_m = f.height_m;
      r.pos_accuracy_m = f.sigma_horizontal_m;
      r.numsats = f.num_satellites;
      SetFixType(f.type, &r);
      stamp = f.stamp;
      next_fix = best + 1;
      ++used;
    } else {
      SetFixType(GnssFixType::kNone, &r);
      if (stamp <= last_stamp) stamp = Timestamp::FromNanoseconds(last_stamp.nanoseconds() + 1);
    }
    // The first record of both streams carries the initial state: KittiDriveReader takes it from
    // the earlier of the two (oxts/ on a tie).
    AttitudeAt(s, stamp, i == 0, &r);
    last_stamp = stamp;
    SLAM_MMS_RETURN_IF_ERROR(writer.AddScan(scan).WithContext(reader.ScanSource(i)));
    SLAM_MMS_RETURN_IF_ERROR(writer.AddOxts(stamp, r));
  }
  if (fixes_dropped != nullptr) *fixes_dropped = s.gnss.size() - used;
  return writer.Finish();
}

}  // namespace slam_mms
