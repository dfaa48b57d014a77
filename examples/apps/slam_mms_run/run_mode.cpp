#include "slam_mms_run/run_mode.hpp"

#include <malloc.h>

#include <chrono>
#include <fstream>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/eval/report.hpp"
#include "slam_mms/io/oxts_record.hpp"
#include "slam_mms_run/progress.hpp"

namespace slam_mms::app {
namespace {

std::string OxtsFile(const KittiRawReader& reader, const char* folder, int64_t index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%010lld.txt", static_cast<long long>(index));
  return (reader.drive_dir() / folder / "data" / name).string();
}

}  // namespace

DriveInput MakeDriveInput(const KittiRawReader& reader) {
  DriveInput in;
  in.reader = &reader;
  in.imu = reader.ImuSamples();
  in.gnss = reader.GnssFixes();
  const char* imu_folder = reader.HasImu100Hz() ? "oxts_100hz" : "oxts";
  for (const StampedOxts& r : reader.ImuOxtsRecords()) {
    in.imu_source.push_back(OxtsFile(reader, imu_folder, r.index));
  }
  for (const StampedOxts& r : reader.OxtsRecords()) {
    in.gnss_source.push_back(OxtsFile(reader, "oxts", r.index));
  }
  // The POS starts from the earliest OXTS record: attitude and velocity (the position comes from
  // the first valid fix, which anchors the world frame).
  const StampedOxts* first = nullptr;
  const char* first_folder = "oxts";
  if (!reader.OxtsRecords().empty()) first = &reader.OxtsRecords().front();
  if (!reader.ImuOxtsRecords().empty() &&
      (first == nullptr || reader.ImuOxtsRecords().front().stamp < first->stamp)) {
    first = &reader.ImuOxtsRecords().front();
    first_folder = imu_folder;
  }
  if (first != nullptr) {
    InsState s;
    s.stamp = first->stamp;
    s.T_world_body.linear() = OxtsAttitude(first->record);
    s.v_world_mps = Eigen::Vector3d(first->record.ve, first->record.vn, first->record.vu);
    in.initial_pos = s;
    in.initial_pos_source = OxtsFile(reader, first_folder, first->index);
  }
  return in;
}

bool ResetPeakRss() {
  malloc_trim(0);
  std::ofstream f("/proc/self/clear_refs");
  if (!f) return false;
  f << "5";
  f.flush();
  return static_cast<bool>(f);
}

ModeRun RunMode(MappingMode mode, const MappingSystem::Options& base_options,
                const DriveInput& input, bool tty) {
  const KittiRawReader& reader = *input.reader;
  ModeRun run;
  run.mode = mode;
  run.name = MappingModeName(mode);
  run.scans_total = reader.NumScans();
  ResetPeakRss();
  const auto t0 = std::chrono::steady_clock::now();

  MappingSystem::Options options = base_options;
  options.mode = mode;
  StatusOr<std::unique_ptr<MappingSystem>> created = MappingSystem::Create(options);
  if (!created.ok()) {
    run.status = created.status();
    return run;
  }
  std::unique_ptr<MappingSystem> system = std::move(created).value();

  ProgressReporter progress(run.name, run.scans_total, tty);
  size_t processed = 0;
  system->SetResultCallback([&](const LocalizationResult&) { progress.Update(++processed); });

  Status status;
  if (input.initial_pos) {
    status = system->InitializePos(*input.initial_pos).WithContext(input.initial_pos_source);
  }
  // Merge the three streams in time order; a scan enters once the IMU/GNSS streams reached its end
  // (at equal stamps: IMU, then GNSS, then the scan).
  size_t i_imu = 0, i_gnss = 0, i_scan = 0;
  const size_t n_imu = input.imu.size(), n_gnss = input.gnss.size(), n_scan = run.scans_total;
  while (status.ok() && (i_imu < n_imu || i_gnss < n_gnss || i_scan < n_scan)) {
    const int64_t kNever = INT64_MAX;
    const int64_t t_imu = i_imu < n_imu ? input.imu[i_imu].stamp.nanoseconds() : kNever;
    const int64_t t_gnss = i_gnss < n_gnss ? input.gnss[i_gnss].stamp.nanoseconds() : kNever;
    const int64_t t_scan = i_scan < n_scan ? reader.ScanEnd(i_scan).nanoseconds() : kNever;
    if (t_imu <= t_gnss && t_imu <= t_scan) {
      status = system->AddImu(input.imu[i_imu]);
      if (!status.ok()) status = status.WithContext(input.imu_source[i_imu]);
      ++i_imu;
    } else if (t_gnss <= t_scan) {
      status = system->AddGnss(input.gnss[i_gnss]);
      if (!status.ok()) status = status.WithContext(input.gnss_source[i_gnss]);
      ++i_gnss;
    } else {
      StatusOr<Scan> scan = reader.ReadScan(i_scan);
      if (!scan.ok()) {
        // One unreadable scan is not fatal: skip it, say which file.
        SLAM_MMS_LOG(kWarning) << "skipping scan " << reader.FrameIndex(i_scan) << ": "
                               << scan.status().ToString();
        ++run.scans_unreadable;
        progress.Update(processed);
      } else {
        if (!run.first_scan_start) run.first_scan_start = scan->stamp_start;
        status = system->AddScan(*scan);
        if (!status.ok()) status = status.WithContext(scan->source);
      }
      ++i_scan;
    }
  }
  if (status.ok()) {
    status = system->Finish();
    run.finished = status.ok();
  }
  run.status = status;
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // What was computed, also after a fatal error (the current estimates).
  run.trajectory = system->FinalTrajectory();
  run.results = system->results();
  run.map = system->FinalMap();
  if (StatusOr<GeodeticPoint> origin = system->Origin(); origin.ok()) run.origin = *origin;
  run.availability = system->GnssAvailability();
  run.scans_skipped_by_system = system->num_skipped_scans();
  run.scans_processed = run.trajectory.size();
  run.scans_per_s = run.wall_s > 0 ? static_cast<double>(run.scans_processed) / run.wall_s : 0.0;
  run.peak_rss_mb = eval::PeakRssMb();
  std::string note;
  const size_t skipped = run.scans_unreadable + static_cast<size_t>(run.scans_skipped_by_system);
  if (skipped > 0) note = "(" + std::to_string(skipped) + " skipped)";
  if (!status.ok()) note += (note.empty() ? "" : " ") + std::string("(stopped by an error)");
  progress.Finish(run.scans_processed, note);
  return run;
}

}  // namespace slam_mms::app
