#pragma once
// Checkpoints of slam_mms_run (--checkpoint-every, --resume; issue 22), in DIR/checkpoint/:
//
//   run.json            {"format": "slam_mms_run checkpoint", "format_version": 1,
//                        "fingerprint": {...what makes two runs the same run...},
//                        "methods": {"<name>": {"state": "complete" | "in_progress",
//                                               "scans_fed": n, "submaps": k}}}
//   <name>.json         a finished method (ModeRun without its map): counts, origin, GNSS
//                       availability, trajectory with covariances, every per-scan result
//   <name>_map.ply      its map (positions and intensities; the per-point stamps are not kept:
//                       its LAS, written when the method finished, has them)
//
// What --resume continues: a method is the unit. Every method that finished (its files written)
// is read back from its checkpoint and not run again; the first method that did not finish is run
// again from the drive's first scan, then the rest. A run is only resumed from a checkpoint with
// the same fingerprint (input, frame range, effective options, outages, POS workflow, simulated
// drive): anything else is an error naming the differing field, before any work.
// --checkpoint-every N: while a method runs, every N finished submaps its trajectory so far is
// written (<name>.tum, as the final one) and run.json records the progress, so a killed run
// (SIGKILL, power loss) leaves the poses computed up to the last checkpoint. The state of a
// running method (its sliding window, surfels and level-2 graph) is not saved, so a method is
// not continued from the middle.
//
// Thread safety: free functions; one run per output folder.

#include <filesystem>
#include <map>
#include <string>

#include "slam_mms/core/status.hpp"
#include "slam_mms_run/run_mode.hpp"

namespace slam_mms::app {

/// The fingerprint's fields: name -> value (a JSON text: string, number, array or object).
using RunFingerprint = std::map<std::string, std::string>;

class Checkpoint {
 public:
  /// Starts a fresh checkpoint in out_dir/checkpoint (any old one is removed).
  static StatusOr<Checkpoint> Start(const std::filesystem::path& out_dir,
                                    const RunFingerprint& fingerprint);
  /// Opens the checkpoint of a killed run. NotFound when there is none; InvalidArgument naming
  /// the first fingerprint field that differs, or when run.json is not a checkpoint.
  static StatusOr<Checkpoint> Resume(const std::filesystem::path& out_dir,
                                     const RunFingerprint& fingerprint);

  /// True where `name` finished in the checkpointed run.
  bool HasFinished(const std::string& name) const;
  /// Reads a finished method back (its map from <name>_map.ply).
  StatusOr<ModeRun> LoadFinished(const std::string& name) const;
  /// Records a finished method (writes <name>.json and <name>_map.ply, then run.json).
  /// `written_map_ply`: where the method's map was just written as a PLY of the same content
  /// (WriteMethodFiles' map_<name>.ply), hard-linked instead of written again; empty, or where
  /// the link fails (another file system), the map is written.
  Status SaveFinished(const ModeRun& run, const std::filesystem::path& written_map_ply = {});
  /// Records the progress of a running method (run.json only).
  Status SaveProgress(const std::string& name, size_t scans_fed, int submaps);
  /// Removes the checkpoint folder (at the end of a run that completed).
  void Remove();

  const std::filesystem::path& dir() const { return dir_; }

 private:
  Status WriteRunJson() const;
  std::filesystem::path dir_;
  std::string fingerprint_json_;
  std::string methods_json_ = "{}";
};

}  // namespace slam_mms::app
