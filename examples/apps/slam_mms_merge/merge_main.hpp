// slam_mms_merge: several drives of one area adjusted into one map (issue 24, docs/merge.md).
//
//   slam_mms_merge --drive OUT1 --drive OUT2 [--drive ...] --out DIR [--las-tile-size M]
//                  [--crs EPSG:nnnn] [--threads N] [--log-level LEVEL]
//
// Each OUTi is a slam_mms_run output folder run with --drive-result (OUTi/drive_result). Writes
// DIR/merged/: map/ (LAS tiles of the merged map, index.json), <drive>.tum and
// <drive>_before.tum (each drive's scan poses after and before, in the common world: the first
// drive's ENU), overlaps.csv (every submap pair tested, its verdict and offsets), georef.json and
// report.json (map entropy of the merged map, of the union of the drives' own maps and, where every
// drive has ground truth, of the union at the true poses; the offset between drives where they
// overlap before and after; per drive its ATE and its maximum error inside its GNSS outages before
// and after, and its GNSS bias). Ground truth is found through OUTi/report.json (input.drive).
#pragma once

namespace slam_mms::app {

/// slam_mms_merge with argv (argv[0] the program name): the exit status (0 done, 1 input or
/// processing error, 2 bad command line).
int MergeMain(int argc, const char* const* argv);

}  // namespace slam_mms::app
