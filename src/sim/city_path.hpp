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

/// Street ids, widths and revisits (a sample on a street driven before) from `o`.
void AssignStreets(const CityWorld::Options& o, std::vector<PathSample>* samples);

}  // namespace slam_mms::sim
