#pragma once
// Ground-truth outputs of the DriveSimulator (private): logs, the scene cloud, scenario.json.
#include <filesystem>
#include <unordered_map>
#include <vector>

#include "core/voxel_grid.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/io/map_io.hpp"
#include "slam_mms/sim/drive_simulator.hpp"

namespace slam_mms::sim {

struct GroundTruthLog {
  Trajectory poses;
  struct Row {
    Timestamp stamp;
    Eigen::Vector3d f_true, w_true, accel_bias, gyro_bias;
    GnssSample gnss;
  };
  std::vector<Row> rows;
  void Add(Timestamp stamp, const BodyState& state, const ImuSample& truth, const ImuSimulator& imu,
           const GnssSample& gnss);
  /// imu_truth.csv and gnss.csv.
  [[nodiscard]] Status WriteCsv(const std::filesystem::path& dir) const;
};

/// Keeps the first point falling into each voxel.
class SceneCloudAccumulator {
 public:
  explicit SceneCloudAccumulator(double voxel_m) : grid_(voxel_m) {}
  /// Keeps the first point of each voxel (internal::VoxelGrid cells); non-finite points and
  /// points beyond the grid's range are dropped.
  void Add(const std::vector<Eigen::Vector3f>& p_world, const std::vector<float>& intensity);
  MapCloud Take();

 private:
  internal::VoxelGrid grid_;
  std::unordered_map<internal::VoxelCell, uint32_t, internal::VoxelCellHash> index_;
  internal::VoxelCell last_cell_;
  bool have_last_ = false;
  MapCloud map_;
};

[[nodiscard]] Status WriteScenarioJson(const DriveSimulator::Options& o, const DriveSimulator& sim,
                                       const DriveSimulator::Summary& summary,
                                       const std::filesystem::path& file);

}  // namespace slam_mms::sim
