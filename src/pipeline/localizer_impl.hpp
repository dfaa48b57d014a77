#pragma once
// Localizer::Impl: level 1's stage objects and the state they share, for the Localizer's files:
//   localizer.cpp          options, Create, ProcessScan (the script of the stages), the API
//   localizer_stages.cpp   the glue between the stage objects: check, begin, predict,
//                          integrate, record
//   localizer_submaps.cpp  the submap life cycle: submap start, close, cut
// The stages (each its own file pair and test): DeskewStage (1), MotionPrior (2),
// ModelRenderStage (3), RegistrationStage (4), WindowStage (5, 6); SurfelMap integrates (7).
// Private to the pipeline module.

#include <cstddef>
#include <map>
#include <memory>
#include <vector>

#include "pipeline/deskew_stage.hpp"
#include "pipeline/model_render_stage.hpp"
#include "pipeline/motion_prior.hpp"
#include "pipeline/registration_stage.hpp"
#include "pipeline/scan_step.hpp"
#include "pipeline/submap_cloud_builder.hpp"
#include "pipeline/submap_store.hpp"
#include "pipeline/window_stage.hpp"
#include "slam_mms/pipeline/localizer.hpp"

namespace slam_mms {

using internal::DeskewedScan;
using internal::Prediction;
using internal::ScanStep;

struct Localizer::Impl {
  Options opt;
  Eigen::Isometry3d T_body_lidar = Eigen::Isometry3d::Identity();
  RangeProjection projection;
  internal::DeskewStage deskew;  ///< 1. de-skew
  /// 2. predict (and the de-skew motion); it keeps the last optimized poses (current submap).
  internal::MotionPrior motion_prior;
  /// The surfels: rendered by step 3, pruned of moving objects by step 4, fused by step 7.
  SurfelMap map;
  /// The map's renderer (borrowed by `map`, which renders the model and the association with it).
  std::unique_ptr<SurfelRenderer> renderer;
  internal::ModelRenderStage model;          ///< 3. render
  internal::RegistrationStage registration;  ///< 4. register
  internal::WindowStage window;              ///< 5. add factors, 6. optimize
  /// The submaps: records, clouds, spill files (the one owner).
  internal::SubmapStore store;
  /// The current submap's map and registration clouds (accumulated off the critical path).
  std::unique_ptr<internal::SubmapCloudBuilder> clouds;
  /// Stable surfels of the submaps that left the live map, by submap id.
  std::map<int32_t, std::vector<Surfel>> archived_surfels;
  std::vector<Surfel> removed_scratch;

  // Level-1 state (all in the current submap's frame).
  bool started = false;
  Eigen::Isometry3d initial_T_world_body = Eigen::Isometry3d::Identity();
  int64_t num_processed = 0;
  /// The previous scan's optimized state (stamp, pose, velocity, biases, POS pose): what the
  /// motion prior predicts from and the next scan's factors tie to.
  internal::PreviousScan prev;
  /// The scan de-skewed and its range image (step 1; reused across scans).
  DeskewedScan deskewed;

  SubmapRecord& current() { return store.current(); }

  // ---- the glue between the stages (localizer_stages.cpp) --------------------------------------
  Status CheckScan(const Scan& scan, const ScanMotionInput& motion) const;
  /// The first scan is the reference of submap 0, at the POS pose (or the initial pose).
  Status StartFirstSubmap(const Scan& scan, const ScanMotionInput& motion);
  ScanStep BeginScan(const Scan& scan, const ScanMotionInput& motion);
  void PredictStage(const Scan& scan, const ScanMotionInput& motion, ScanStep* step,
                    LocalizationResult* res) const;
  Status IntegrateStage(const Scan& scan, const ScanStep& step, LocalizationResult* res);
  /// Bookkeeping: the scan's pose into its submap record, the state the next scan starts from.
  void RecordScan(const Scan& scan, const ScanMotionInput& motion, const ScanStep& step,
                  LocalizationResult* res);

  // ---- the submap life cycle (localizer_submaps.cpp) -------------------------------------------
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
