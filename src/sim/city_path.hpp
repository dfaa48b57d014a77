#pragma once
// The driven path as the city generator sees it (private to the simulator): samples every 0.5 m
// along the trajectory, extended 80 m beyond both ends, and their street attributes (split from
// city_generator.cpp).
//
// Thread safety: pure functions.

#include <vector>

#include "sim/path_index.hpp"
#include "slam_mms/sim/city_world.hpp"
#include "slam_mms/sim/reference_trajectory.hpp"

namespace slam_mms::sim {

/// Samples of the path between t_begin and t_end [s] of `traj` (the body's ground track,
/// body_height [m] above the road), each with its tangent, arc length and road height, extended
/// straight beyond both ends so that streets continue past the drive.
std::vector<PathSample> SamplePath(const ReferenceTrajectory& traj, double t_begin, double t_end,
                                   double body_height);

/// SamplePath of each span, concatenated in order: each path's first sample is marked
/// path_start (no segment joins two paths) and its arc lengths continue the previous path's plus a
/// 100 m gap (so that a later path's samples are all "after" an earlier path's for AssignStreets).
std::vector<PathSample> SamplePaths(const std::vector<CityWorld::PathSpan>& spans,
                                    double body_height);

/// Gives each sample of a straight extension beyond a path's end (which keeps the end's road
/// height) the road height of the nearest driven sample of any path within 2.5 m on a parallel or
/// antiparallel street, so that a driven street that an extension overlaps has its own heights.
void MatchExtensionHeights(std::vector<PathSample>* samples);

/// Street ids, widths and revisits (a sample on a street driven before, in the same direction, or
/// with `either_direction` also in the opposite one) from `o`. A path_start sample starts a new
/// street unless it is a revisit.
void AssignStreets(const CityWorld::Options& o, bool either_direction,
                   std::vector<PathSample>* samples);

}  // namespace slam_mms::sim
