#pragma once
// DeskewStage: step 1 of Localizer::ProcessScan (paper §5.1.2). Every point of the raw scan is
// moved to the scan's start with the body motion over the scan that the motion prior gives
// (MotionPrior::DeskewMotion, from the prediction of step 2), and the de-skewed scan's range image
// (vertex/normal map) is computed for registration and surfel integration.
//
// The motion source is the scan's own ScanMotionInput, whatever factor ties the scan to the
// previous one: a scan with POS poses is de-skewed by the POS motion even where it gets no F_Odom
// (a submap reference, or no POS pose for the previous scan).
//
// Ownership: owns the de-skewer and the range-image threads; the output (DeskewedScan) is the
// caller's. Thread safety: not thread-safe.

#include <Eigen/Geometry>
#include <memory>

#include "pipeline/motion_prior.hpp"
#include "pipeline/scan_deskewer.hpp"
#include "pipeline/scan_step.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/localizer.hpp"
#include "slam_mms/surfel/range_projection.hpp"
#include "surfel/parallel_range_image.hpp"

namespace slam_mms::internal {

class DeskewStage {
 public:
  DeskewStage() = default;
  /// Uses options.deskew and num_threads. InvalidArgument from ScanDeskewer::Create.
  static StatusOr<DeskewStage> Create(const Localizer::Options& options,
                                      const RangeProjection& projection,
                                      const Eigen::Isometry3d& T_body_lidar);

  /// De-skews `scan` into out->cloud (lidar frame at the scan start) and computes out->vnm, with
  /// the motion `prior` gives from step->pred (and the IMU biases `bias`), which it keeps in
  /// step->T_bstart_bend and step->constant_velocity_deskew; the time into `res`.
  /// InvalidArgument from ScanDeskewer::Deskew.
  Status Deskew(const Scan& scan, const ScanMotionInput& motion, const MotionPrior& prior,
                const Vector6d& bias, ScanStep* step, DeskewedScan* out, LocalizationResult* res);
  /// The same with a given body motion over the scan (the time is added to `res`'s).
  Status DeskewWith(const Scan& scan, const Eigen::Isometry3d& T_bstart_bend, DeskewedScan* out,
                    LocalizationResult* res);

 private:
  ScanDeskewer deskewer_;
  RangeProjection projection_;
  Eigen::Isometry3d T_body_lidar_ = Eigen::Isometry3d::Identity();
  std::unique_ptr<ParallelRangeImage> range_image_;
};

}  // namespace slam_mms::internal
