#pragma once
// LocalizationResult: what level 1 (Localizer) reports for every scan, and the per-stage timings.
//
// Thread safety: value type.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/registration/registration_result.hpp"

namespace slam_mms {

/// The mapping method (paper §6): the SLAM-integrated system, the traditional MMS (POS only: the
/// forward filter as in real time, or the post-processed forward-backward smoothed POS) and the
/// SuMa-like LiDAR-only baseline. kGnssInsSmoothed is offline only: RunDrive smooths the whole
/// IMU/GNSS stream first (PosSmoother), then places the scans with it through a kGnssIns
/// MappingSystem fed the smoothed POS (AddInsPose); MappingSystem::Create rejects it.
enum class MappingMode { kFull = 0, kGnssIns = 1, kLidarOnly = 2, kGnssInsSmoothed = 3 };
/// "full", "gnss_ins", "lidar_only", "gnss_ins_smoothed".
const char* MappingModeName(MappingMode mode);
/// Parses "full" / "gnss_ins" / "lidar_only" / "gnss_ins_smoothed".
bool ParseMappingMode(const std::string& name, MappingMode* mode);

/// Which motion factor level 1 used for a scan (the explicit switch of paper §5.1.1).
enum class MotionFactorType {
  kNone = 0,          ///< First scan, or no motion information.
  kOdometry,          ///< F_Odom (eq 12): GNSS/INS relative motion, GNSS valid.
  kPreintegration,    ///< F_Prein (eq 14): IMU preintegration, GNSS lost.
  kConstantVelocity,  ///< LiDAR-only: a weak constant-velocity prior.
  kPos,               ///< gnss_ins mode: the POS pose is the result.
};
const char* MotionFactorTypeName(MotionFactorType type);

/// Milliseconds spent per stage of ProcessScan (paper order).
struct StageTimings {
  double deskew_ms = 0.0;
  double predict_ms = 0.0;
  double render_ms = 0.0;
  double register_ms = 0.0;
  double factors_ms = 0.0;
  double optimize_ms = 0.0;
  double integrate_ms = 0.0;
  double total_ms = 0.0;
  static constexpr int kNumStages = 7;
  static const std::array<const char*, kNumStages>& Names();
  std::array<double, kNumStages> Values() const {
    return {deskew_ms, predict_ms, render_ms, register_ms, factors_ms, optimize_ms, integrate_ms};
  }
};

struct LocalizationResult {
  int64_t scan_index = -1;  ///< Scan::index.
  Timestamp stamp;          ///< The scan's reference time (its first point, stamp_start).
  int32_t submap_id = 0;
  bool new_submap = false;  ///< This scan started submap submap_id (it is its reference).
  /// Level-1 pose (before any later level-2 correction) and its covariance (rotation first).
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  Matrix6d cov_T_world_body = Matrix6d::Identity();
  MotionFactorType motion_factor = MotionFactorType::kNone;
  // Registration (F_Reg, eq 16).
  bool registered = false;         ///< ICP ran against a non-empty model.
  bool registration_used = false;  ///< Its factor entered the graph (passed consistency).
  bool registration_downweighted = false;
  IcpTermination termination = IcpTermination::kMaxIterations;
  size_t num_inliers = 0;
  double inlier_ratio = 0.0;
  double rms_residual_m = 0.0;
  int icp_iterations = 0;
  bool degenerate = false;  ///< Some direction weakly observed (tunnel, open field).
  Vector6d degeneracy_axis_information = Vector6d::Zero();  ///< Per axis, see DegeneracyAnalysis.
  double consistency_mahalanobis_sq = 0.0;
  /// Moving objects left out of registration, fusion and the map (Level1Options::dynamic), and
  /// their pixels.
  int num_moving_objects = 0;
  int num_moving_pixels = 0;
  // Map.
  size_t num_surfels = 0;
  size_t num_model_surfels = 0;  ///< Surfels rendered for registration.
  StageTimings timings;
};

}  // namespace slam_mms
