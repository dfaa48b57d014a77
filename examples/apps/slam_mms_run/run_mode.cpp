#include "slam_mms_run/run_mode.hpp"

#include <malloc.h>

#include <fstream>

#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/eval/report.hpp"
#include "slam_mms_run/progress.hpp"

namespace slam_mms::app {

bool ResetPeakRss() {
  malloc_trim(0);
  std::ofstream f("/proc/self/clear_refs");
  if (!f) return false;
  f << "5";
  f.flush();
  return static_cast<bool>(f);
}

ModeRun RunMode(MappingMode mode, const MappingSystem::Options& base_options,
                const DriveReader& reader, PosWorkflow pos, bool tty, const std::atomic<bool>* stop,
                std::function<void(const MappingSystem&, int)> on_submap,
                std::function<void(const MappingSystem&)> on_finished) {
  ModeRun run;
  run.mode = mode;
  run.name = MappingModeName(mode);
  run.scans_total = reader.NumScans();
  ResetPeakRss();

  MappingSystem::Options options = base_options;
  options.mode = mode;
  ProgressReporter progress(run.name, run.scans_total, tty);
  DriveRunCallbacks callbacks;
  callbacks.on_scan = [&](size_t fed, size_t) { progress.Update(fed); };
  callbacks.stop = stop;
  callbacks.on_submap = std::move(on_submap);
  callbacks.on_finished = std::move(on_finished);
  DriveRunOptions run_options;
  run_options.pos = pos;
  DriveRun d = RunDrive(reader, options, callbacks, run_options);

  run.trajectory = std::move(d.trajectory);
  run.results = std::move(d.results);
  run.map = std::move(d.map);
  run.map_stamps = std::move(d.map_stamps);
  run.origin = d.origin;
  run.availability = std::move(d.availability);
  run.first_scan_start = d.first_scan_start;
  run.wall_s = d.wall_s;
  run.scans_processed = d.scans_processed;
  run.scans_unreadable = d.scans_unreadable;
  run.scans_skipped_by_system = d.scans_skipped_by_system;
  run.skipped_scans = std::move(d.skipped_scans);
  run.finished = d.finished;
  run.complete = d.complete;
  run.stopped = d.finished && !d.complete && d.status.ok() && stop != nullptr && stop->load();
  run.smoothed_pos = d.smoothed_pos;
  run.status = d.status;
  run.scans_per_s = run.wall_s > 0 ? static_cast<double>(run.scans_processed) / run.wall_s : 0.0;
  run.peak_rss_mb = eval::PeakRssMb();
  std::string note;
  const size_t skipped = run.scans_unreadable + static_cast<size_t>(run.scans_skipped_by_system);
  if (skipped > 0) note = "(" + std::to_string(skipped) + " skipped)";
  if (run.mode == MappingMode::kFull && run.smoothed_pos) {
    note += (note.empty() ? "" : " ") + std::string("(on the smoothed POS)");
  }
  if (!run.status.ok()) note += (note.empty() ? "" : " ") + std::string("(stopped by an error)");
  if (run.stopped) note += (note.empty() ? "" : " ") + std::string("(stopped by a signal)");
  progress.Finish(run.scans_processed, note);
  return run;
}

}  // namespace slam_mms::app
