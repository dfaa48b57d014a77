#pragma once
// Test helper: simulates a drive once per test process (ctest runs each test in its own process,
// two at a time) into a private temp folder and keeps what the pipeline tests compare with.
#include <unistd.h>

#include <filesystem>
#include <string>
#include <utility>

#include "slam_mms/ins/gnss_prior.hpp"  // GeodeticPoint
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms/sim/drive_simulator.hpp"

namespace slam_mms::testing {

struct SimulatedDrive {
  std::filesystem::path dir;        ///< The temp folder (remove it when done).
  std::filesystem::path drive_dir;  ///< The KITTI-raw drive inside it.
  GeodeticPoint origin;             ///< The simulator's world origin.
  Trajectory ground_truth;          ///< T_world_body at each scan's start.
  Trajectory poses_100hz;           ///< T_world_body at 100 Hz.
};

/// Simulates `duration_s` seconds of the default drive with `seed` (no scene cloud) into
/// temp/<name>_<pid>.
inline StatusOr<SimulatedDrive> SimulateDrive(const std::string& name, uint64_t seed,
                                              double duration_s) {
  SimulatedDrive d;
  d.dir = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  sim::DriveSimulator::Options opt;
  opt.seed = seed;
  opt.duration_s = duration_s;
  opt.write_scene_cloud = false;
  SLAM_MMS_ASSIGN_OR_RETURN(sim::DriveSimulator simulator, sim::DriveSimulator::Create(opt));
  SLAM_MMS_ASSIGN_OR_RETURN(const sim::DriveSimulator::Summary summary, simulator.Run(d.dir));
  d.drive_dir = summary.drive_dir;
  d.origin =
      GeodeticPoint{simulator.options().origin_latitude_deg,
                    simulator.options().origin_longitude_deg, simulator.options().origin_height_m};
  SLAM_MMS_ASSIGN_OR_RETURN(d.ground_truth,
                            ReadTrajectoryTum(d.drive_dir / "ground_truth" / "scan_start.tum"));
  SLAM_MMS_ASSIGN_OR_RETURN(d.poses_100hz,
                            ReadTrajectoryTum(d.drive_dir / "ground_truth" / "poses_100hz.tum"));
  return d;
}

}  // namespace slam_mms::testing
