#pragma once
// RegistrationStage: step 4 of Localizer::ProcessScan, the F_Reg measurement (paper §5.1.2,
// eq 15-16). The de-skewed scan's range image is aligned to the model image rendered at the
// prediction by ProjectiveIcp (frame-to-model, point-to-plane); a usable result becomes the
// scan's body pose in the submap and its covariance:
//   T_submap_body = T_world_submap^-1 * T_world_lidar_pred * T_lidar_pred_lidar * T_lidar_body
//   cov = reg_cov_scale * Ad(T_body_lidar) cov_icp Ad(T_body_lidar)^T + diag(floor^2)
// Before the alignment, moving objects (DynamicObjectFilter) are masked out of the scan's image
// and cloud, and the surfels they were seen through leave the map, where the prediction is good
// enough to judge by (from the POS or the IMU, not constant velocity).
//
// Ownership: owns the ICP, the moving-object filter and the path travelled (the filter's model
// age); the scan, the model and the map are the caller's. Thread safety: not thread-safe.

#include <Eigen/Geometry>
#include <cstdint>

#include "pipeline/dynamic_objects.hpp"
#include "pipeline/scan_step.hpp"
#include "registration/projective_icp.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/localizer.hpp"
#include "slam_mms/surfel/range_projection.hpp"
#include "slam_mms/surfel/surfel_map.hpp"
#include "slam_mms/surfel/vertex_normal_map.hpp"

namespace slam_mms::internal {

class RegistrationStage {
 public:
  RegistrationStage() = default;
  /// Uses options.icp, num_threads, dynamic, min_inlier_ratio, reg_cov_scale and the
  /// registration sigma floors. InvalidArgument from ProjectiveIcp::Create.
  static StatusOr<RegistrationStage> Create(const Localizer::Options& options,
                                            const RangeProjection& projection,
                                            const Eigen::Isometry3d& T_body_lidar);

  /// Registers the scan where step->have_model and it is not a submap reference: sets
  /// step->T_submap_reg and step->cov_reg when the result is usable (inlier ratio at least
  /// min_inlier_ratio, finite), the ICP's outcome and the moving objects into `res`. `model` was
  /// rendered at step->T_world_lidar_pred; moving objects are masked out of `scan` and their
  /// old surfels removed from `map`.
  Status Register(const Scan& raw, const VertexNormalMap& model, DeskewedScan* scan, SurfelMap* map,
                  ScanStep* step, LocalizationResult* res);
  /// Registers the scan again (de-skewed anew) from the relative pose `T_lidar_pred_lidar` (lidar
  /// at the prediction to lidar), without the moving-object filter: replaces what Register set
  /// (step->T_submap_reg is empty where this result is not usable); the time is added to res's.
  Status Reregister(const Scan& raw, const VertexNormalMap& model,
                    const Eigen::Isometry3d& T_lidar_pred_lidar, DeskewedScan* scan, ScanStep* step,
                    LocalizationResult* res);

  /// A processed scan's stamp and body position (world): the path the filter's model age is
  /// measured along.
  void RecordPose(int64_t stamp_ns, const Eigen::Vector3d& p_world);

 private:
  /// Register and Reregister: ICP from `T_lidar_pred_lidar`, after the moving-object filter
  /// where `map` is given (its surfels seen through moving objects are removed).
  Status Align(const Scan& raw, const VertexNormalMap& model,
               const Eigen::Isometry3d& T_lidar_pred_lidar, DeskewedScan* scan, SurfelMap* map,
               ScanStep* step, LocalizationResult* res);
  /// The moving-object filter on the scan, at the prediction.
  void FilterMovingObjects(const VertexNormalMap& model, DeskewedScan* scan, SurfelMap* map,
                           const ScanStep& step, LocalizationResult* res);

  DynamicObjectOptions dynamic_options_;
  double min_inlier_ratio_ = 0.0;
  double reg_cov_scale_ = 1.0;
  double reg_sigma_floor_rot_rad_ = 0.0;
  double reg_sigma_floor_trans_m_ = 0.0;
  Eigen::Isometry3d T_body_lidar_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_lidar_body_ = Eigen::Isometry3d::Identity();
  ProjectiveIcp icp_;
  DynamicObjectFilter dynamic_;
  TravelHistory travel_;
};

}  // namespace slam_mms::internal
