#pragma once
// Localizer::Impl: level 1's stage objects and the state they share, for the Localizer's files:
//   localizer.cpp          options, Create, ProcessScan (the script of the stages), the API
//   localizer_stages.cpp   the glue between the stage objects: check, first submap, begin,
//                          predict, record, submap cut
// The stages (each its own file pair and test): DeskewStage (1), MotionPrior (2),
// ModelRenderStage (3), RegistrationStage (4), WindowStage (5, 6), IntegrationStage (7 and the
// submap life cycle).
// Private to the pipeline module.

#include <memory>

#include "pipeline/deskew_stage.hpp"
#include "pipeline/integration_stage.hpp"
#include "pipeline/model_render_stage.hpp"
#include "pipeline/motion_prior.hpp"
#include "pipeline/registration_stage.hpp"
#include "pipeline/scan_step.hpp"
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
  /// 7. integrate, and the submaps (records, clouds, spill files; the one owner).
  internal::IntegrationStage integration;

  // Level-1 state (all in the current submap's frame).
  bool started = false;
  Eigen::Isometry3d initial_T_world_body = Eigen::Isometry3d::Identity();
  int64_t num_processed = 0;
  /// The previous scan's optimized state (stamp, pose, velocity, biases, POS pose): what the
  /// motion prior predicts from and the next scan's factors tie to.
  internal::PreviousScan prev;
  /// The scan de-skewed and its range image (step 1; reused across scans).
  DeskewedScan deskewed;

  SubmapRecord& current() { return integration.current(); }

  // ---- the glue between the stages (localizer_stages.cpp) --------------------------------------
  Status CheckScan(const Scan& scan, const ScanMotionInput& motion) const;
  /// The first scan is the reference of submap 0, at the POS pose (or the initial pose).
  Status StartFirstSubmap(const Scan& scan, const ScanMotionInput& motion);
  ScanStep BeginScan(const Scan& scan, const ScanMotionInput& motion);
  void PredictStage(const Scan& scan, const ScanMotionInput& motion, ScanStep* step,
                    LocalizationResult* res) const;
  /// 4b. A constant-velocity de-skew refined (Options::refine_constant_velocity_deskew): the
  /// scan de-skewed again at the motion between the middles of the previous sweep and this one
  /// (this one's from the first registration), and registered again from there.
  Status RefineConstantVelocityDeskew(const Scan& scan, ScanStep* step, LocalizationResult* res);
  /// Bookkeeping: the scan's pose into its submap record, the state the next scan starts from.
  void RecordScan(const Scan& scan, const ScanMotionInput& motion, const ScanStep& step,
                  LocalizationResult* res);

  /// The submap cut every WT (end of ProcessScan): `scan`, recorded, becomes the reference of a
  /// new submap; the level-1 state (motion prior, previous scan, window) is re-expressed in it.
  Status CutSubmap(const Scan& scan, const ScanStep& step, LocalizationResult* res);
};

}  // namespace slam_mms
