#pragma once
// Localizer::Impl: level 1's state and the stages of ProcessScan, shared by the Localizer's files:
//   localizer.cpp          options, Create, ProcessScan (the script of the stages), the API
//   localizer_stages.cpp   the stages: check, predict, de-skew, render, register, factors,
//                          optimize, integrate, record
//   localizer_motion.cpp   the motion prior: prediction, de-skew motion, F_Odom / F_Prein / CV
//   localizer_submaps.cpp  the submap life cycle: window start, submap start, close, cut
// Private to the pipeline module.

#include <chrono>
#include <cstddef>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "backend/sliding_window_graph.hpp"
#include "pipeline/dynamic_objects.hpp"
#include "pipeline/motion_prior.hpp"
#include "pipeline/scan_deskewer.hpp"
#include "pipeline/submap_cloud_builder.hpp"
#include "pipeline/submap_store.hpp"
#include "registration/projective_icp.hpp"
#include "slam_mms/pipeline/localizer.hpp"
#include "surfel/parallel_range_image.hpp"

namespace ceres {
class CostFunction;
}

namespace slam_mms {

using Clock = std::chrono::steady_clock;

inline double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

namespace internal {
/// A prior x ~ N(mean, sigma^2 I) on a block of size N, as a ceres::NormalPrior.
std::unique_ptr<ceres::CostFunction> MakeNormalPrior(const Eigen::VectorXd& mean,
                                                     const Eigen::VectorXd& sigma);
}  // namespace internal

using internal::Prediction;

/// One scan's working values, handed from stage to stage of ProcessScan.
struct ScanStep {
  Eigen::Isometry3d T_world_submap = Eigen::Isometry3d::Identity();  ///< The current submap's.
  Eigen::Vector3d g_submap = Eigen::Vector3d::Zero();                ///< Gravity in the submap.
  bool is_reference = false;  ///< The scan is its submap's reference (first scan).
  Prediction pred;            ///< 2. predict
  Eigen::Isometry3d T_world_lidar_pred = Eigen::Isometry3d::Identity();  ///< 3. render
  bool have_model = false;                                               ///< 3. render
  std::optional<Eigen::Isometry3d> T_submap_reg;  ///< 4. register: the usable result
  Matrix6d cov_reg = Matrix6d::Identity();        ///< 4. register: its covariance
  StateId cur_state = 0;                          ///< 5. factors: the scan's window state
  Eigen::Isometry3d T_submap_cur = Eigen::Isometry3d::Identity();  ///< 6. optimize
};

struct Localizer::Impl {
  Options opt;
  Eigen::Isometry3d T_body_lidar = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_lidar_body = Eigen::Isometry3d::Identity();
  RangeProjection projection;
  ScanDeskewer deskewer;
  SurfelMap map;
  std::unique_ptr<SurfelRenderer> renderer;
  ProjectiveIcp icp;
  internal::DynamicObjectFilter dynamic;
  /// The path travelled (per scan stamp), for the filter's model age.
  internal::TravelHistory travel;
  std::unique_ptr<SlidingWindowGraph> window;
  /// The submaps: records, clouds, spill files (the one owner).
  internal::SubmapStore store;
  /// The current submap's map and registration clouds (accumulated off the critical path).
  std::unique_ptr<internal::SubmapCloudBuilder> clouds;
  /// The scan's range image, on the Localizer's threads.
  std::unique_ptr<internal::ParallelRangeImage> range_image;
  bool use_imu_states = false;
  /// Stable surfels of the submaps that left the live map, by submap id.
  std::map<int32_t, std::vector<Surfel>> archived_surfels;
  std::vector<Surfel> removed_scratch;

  // Level-1 state (all in the current submap's frame).
  bool started = false;
  Eigen::Isometry3d initial_T_world_body = Eigen::Isometry3d::Identity();
  StateId next_id = 0;
  StateId ref_id = 0;
  StateId prev_id = 0;
  int64_t num_processed = 0;
  /// The previous scan's optimized state (stamp, pose, velocity, biases, POS pose): what the
  /// motion prior predicts from and the next scan's factors tie to.
  internal::PreviousScan prev;
  /// Step 2 and the de-skew motion; it keeps the last optimized poses (current submap frame).
  internal::MotionPrior motion_prior;

  // Scratch, reused across scans.
  PointCloud deskewed;
  VertexNormalMap scan_vnm;
  VertexNormalMap model_vnm;
  std::vector<uint32_t> active_ids;
  std::vector<uint32_t> model_ids;

  SubmapRecord& current() { return store.current(); }

  // ---- the stages of ProcessScan (localizer_stages.cpp) ----------------------------------------
  Status CheckScan(const Scan& scan, const ScanMotionInput& motion) const;
  /// The first scan is the reference of submap 0, at the POS pose (or the initial pose).
  Status StartFirstSubmap(const Scan& scan, const ScanMotionInput& motion);
  ScanStep BeginScan(const Scan& scan, const ScanMotionInput& motion);
  void PredictStage(const Scan& scan, const ScanMotionInput& motion, ScanStep* step,
                    LocalizationResult* res) const;
  Status DeskewStage(const Scan& scan, const ScanMotionInput& motion, const ScanStep& step,
                     LocalizationResult* res);
  Status RenderStage(const Scan& scan, ScanStep* step, LocalizationResult* res);
  Status RegisterStage(const Scan& scan, ScanStep* step, LocalizationResult* res);
  Status FactorStage(const Scan& scan, const ScanMotionInput& motion, ScanStep* step,
                     LocalizationResult* res);
  Status OptimizeStage(const Scan& scan, ScanStep* step, LocalizationResult* res);
  Status IntegrateStage(const Scan& scan, const ScanStep& step, LocalizationResult* res);
  /// Bookkeeping: the scan's pose into its submap record, the state the next scan starts from.
  void RecordScan(const Scan& scan, const ScanMotionInput& motion, const ScanStep& step,
                  LocalizationResult* res);

  // ---- the motion factor (localizer_motion.cpp) ------------------------------------------------

  /// Step 5 of ProcessScan, the motion factor between the previous scan's state and `cur_state`:
  /// F_Odom (eq 12), F_Prein (eq 14) or the constant-velocity factor. Returns its covariance (the
  /// registration's consistency check uses it).
  StatusOr<Matrix6d> AddMotionFactor(StateId cur_state, const ScanMotionInput& motion,
                                     const Prediction& pred, double dt,
                                     const Eigen::Isometry3d& T_world_submap,
                                     const Eigen::Vector3d& g_submap);

  // ---- the submap life cycle (localizer_submaps.cpp) -------------------------------------------
  Status StartWindow(const Eigen::Vector3d& v_submap, const Vector6d& bias);

  void StartSubmap(const Eigen::Isometry3d& T_world_submap, Timestamp stamp, int64_t scan_index,
                   const Eigen::Isometry3d& T_prev_this, const Matrix6d& cov_prev_this);

  /// Takes the surfels of submaps older than current_id - 1 out of the live map (archiving the
  /// stable ones when asked).
  void RetireOldSurfels(int32_t current_id);

  void CloseCurrentSubmap();

  /// The submap cut every WT (end of ProcessScan): `scan`, at T_submap_cur in the current submap,
  /// becomes the reference of a new submap; the level-1 state is re-expressed in it.
  Status CutSubmap(const Scan& scan, const Eigen::Isometry3d& T_world_submap,
                   const Eigen::Isometry3d& T_submap_cur, LocalizationResult* res);
};

}  // namespace slam_mms
