#pragma once
// Localizer: level 1 of the hierarchical factor graph (paper §5.1, Fig. 4 left, eqs 12-16).
//
// ProcessScan is a short script of named stages, in the paper's order:
//   1. de-skew      every point to the scan's first-point time with the motion prior
//                   (POS while GNSS is valid, IMU preintegration while it is lost, constant
//                   velocity in LiDAR-only mode)                                           §5.1.2
//   2. predict      the scan's pose from the previous optimized state and the motion prior
//   3. render       the current (and previous) submap's surfels at the prediction  §5.1.2
//   4. register     ProjectiveIcp scan-to-submap (F_Reg measurement, eq 15-16)
//   5. add factors  F_Reg between the submap reference and the scan (consistency-checked against
//   the
//                   motion prediction, Graham et al. 2015); the motion factor between consecutive
//                   scans: F_Odom (eq 12) from the POS while GNSS is valid, F_Prein (eq 14) from
//                   IMU preintegration while it is lost (an explicit, logged switch), or a weak
//                   constant-velocity factor (LiDAR only)
//   6. optimize     SlidingWindowGraph (Levenberg-Marquardt, <= 100 iterations, marginalization)
//   7. integrate    the scan's surfels into the map at the optimized pose
// Every Options::submap_duration_s (WT, default 5 s as in the paper) a new submap starts; its
// reference frame is the body pose of its first scan. The level-1 window works in the frame of the
// current submap (states T_submap_scan), so level-2 corrections of T_world_submap never disturb it.
//
// The level-1 graph's state of scan i holds the pose T_submap_body and, where IMU is used, the
// velocity and IMU biases (estimated with a prior, beyond the paper, which fixes them).
//
// Ownership: owns its surfel map, renderer, ICP and window. Move-only via unique_ptr.
// Thread safety: not thread-safe.

#include <Eigen/Geometry>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include "slam_mms/backend/sliding_window_options.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"
#include "slam_mms/pipeline/deskew_options.hpp"
#include "slam_mms/pipeline/dynamic_object_options.hpp"
#include "slam_mms/pipeline/localization_result.hpp"
#include "slam_mms/pipeline/map_point_stamps.hpp"
#include "slam_mms/pipeline/submap_source.hpp"
#include "slam_mms/registration/registration_options.hpp"
#include "slam_mms/surfel/surfel_map.hpp"

namespace slam_mms {

/// The motion information the host (MappingSystem) gives level 1 for one scan.
struct ScanMotionInput {
  /// kOdometry: POS poses at this scan's start and end (world), and the 1-sigma noise of the POS
  /// relative motion per scan interval; kPreintegration: `imu` covers [previous scan start,
  /// this scan end]; kConstantVelocity: nothing. The Localizer switches by this field.
  MotionFactorType type = MotionFactorType::kConstantVelocity;
  Eigen::Isometry3d T_world_body_pos_start = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_world_body_pos_end = Eigen::Isometry3d::Identity();
  Eigen::Vector3d v_world_pos = Eigen::Vector3d::Zero();  ///< POS velocity at scan start.
  Vector6d pos_bias = Vector6d::Zero();                   ///< POS bias estimate [ba, bg].
  std::vector<ImuSample> imu;
  Eigen::Vector3d g_world = Eigen::Vector3d(0.0, 0.0, -9.80665);
};

/// SurfelMapOptions with level 1's image width (see Level1Options::surfels).
SurfelMapOptions DefaultLevel1SurfelOptions();

/// Level 1's settings: what MappingSystem::Options::localizer carries (config keys
/// "localizer.*"). The mode, the map output and the threads belong to the owner
/// (MappingSystem::Options, or Localizer::Options for a Localizer used on its own), so each is set
/// in one place.
struct Level1Options {
  double submap_duration_s = 5.0;  ///< WT [s], > 0.
  /// Includes the range-image geometry: 64 x 1024 (an HDL-64E gives ~2000 firings a turn; SuMa
  /// uses 900 columns for KITTI; 1024 halves the per-pixel work of 2048 and measured as
  /// accurate on the simulated drive).
  SurfelMapOptions surfels = DefaultLevel1SurfelOptions();
  ProjectiveIcpOptions icp;
  SlidingWindowOptions window;
  DeskewOptions deskew;
  /// Moving objects kept out of registration, the surfel map and the point-cloud map.
  DynamicObjectOptions dynamic;
  ImuPreintegration::Options imu;
  SurfelRendererBackend renderer = SurfelRendererBackend::kAuto;
  /// Surfels rendered for registration: those within this radius with confidence above
  /// min_model_confidence (SuMa: 0, the stable ones; over the first 10 scans the threshold ramps
  /// up from ln(0.1/0.9) as in SuMa), of the current submap and, while the current one is younger
  /// than previous_submap_model_s, of the previous one too [m, -, s].
  double model_radius_m = 60.0;
  float min_model_confidence = 0.0f;
  double previous_submap_model_s = 2.5;
  /// F_Odom noise per scan interval (1 sigma): rotation [rad] and translation [m].
  double odom_sigma_rot_rad = 0.002;
  double odom_sigma_trans_m = 0.02;
  /// LiDAR only: constant-velocity factor noise per scan interval.
  double cv_sigma_rot_rad = 0.02;
  double cv_sigma_trans_m = 0.3;
  /// Registration covariance: max(icp covariance * scale, floor^2) per axis.
  double reg_cov_scale = 100.0;
  double reg_sigma_floor_rot_rad = 0.0005;
  double reg_sigma_floor_trans_m = 0.01;
  /// Registration rejected when the inlier ratio is below this.
  double min_inlier_ratio = 0.2;
  /// Voxel of the per-submap registration cloud (level 2's map-to-map ICP and loops) [m].
  double registration_voxel_m = 0.5;
  /// Each submap has its own surfels (the paper's local maps): a scan is fused only into the
  /// current submap, and registration sees the current and the previous submap. Once a submap is
  /// two behind, its surfels leave the live map (bounded work and memory on long drives; a
  /// revisited place is not fused into old surfels but closed as a loop by level 2). Off: one
  /// live map, every scan fused into any surfel it sees. It sets the surfel map's
  /// integrate_current_submap_only (surfels.integrate_current_submap_only must stay false).
  bool per_submap_surfels = true;
  /// Keep the stable surfels (confidence > surfels.confidence_threshold) of the submaps that
  /// left the live map, for AllSurfels(). Off by default: they grow with the drive (measured
  /// +0.3 MB a scan, 385 MB after 2 min), while the point-cloud map is the product's output.
  bool archive_surfels = false;
  /// lidar_only starts from the POS's velocity at its first scan as well as its pose (both the
  /// initial state it is anchored at): its first scans are de-skewed at that velocity, where
  /// otherwise the first two are not de-skewed at all (no velocity before two registered scans),
  /// which smears the map it starts from by the motion of a sweep (0.3-0.9 m at 3-9 m/s) and
  /// costs 0.15-0.4 m of drift on drives that start moving (docs/sweep.md, session 18). After
  /// that, LiDAR only.
  bool lidar_only_initial_velocity = true;
  /// A scan de-skewed at constant velocity (lidar_only; no POS and no IMU) is registered twice:
  /// the first registration fixes the pose at the middle of the sweep (a wrong rate shears the
  /// scan symmetrically about it), and the scan is de-skewed again at the motion between the
  /// middles of the previous sweep and this one, and registered again. The velocity of the last
  /// three intervals alone lags the motion by two scans: on vehicles that pitch and roll at 1-4
  /// deg/s (real OXTS motion) the scan-start poses were 70 mdeg off in roll and pitch, against
  /// 18 mdeg with the motion between the middles (docs/pipeline.md). Costs a second de-skew and
  /// registration of each such scan.
  bool refine_constant_velocity_deskew = true;
  /// Bounded memory on long drives: where finished submaps' point clouds go. Empty (default):
  /// they stay in memory. Otherwise a private folder is created inside it (an error at Create
  /// when that fails) and removed with the Localizer; a submap's map cloud is written there when
  /// the submap is finished and its registration cloud when it is two behind, and read back on
  /// demand (SubmapCloud: the final map, loop closure). A failed write keeps the cloud in memory
  /// (logged); nothing is lost.
  std::filesystem::path spill_dir;
  /// InvalidArgument naming "Localizer::Options::<field>".
  [[nodiscard]] Status Validate() const;
};

class Localizer final : public SubmapSource {
 public:
  /// Level 1's settings plus what its owner decides: MappingSystem fills these from its own
  /// Options (mode, map_voxel_m, map_max_range_m, num_threads).
  struct Options : Level1Options {
    MappingMode mode = MappingMode::kFull;
    /// Map output: voxel of the per-submap point cloud [m], points up to this range [m].
    double map_voxel_m = 0.1;
    double map_max_range_m = 60.0;
    /// Threads of every level-1 stage (de-skew, range image, ICP, window solve, surfel update,
    /// CPU render), the calling thread included; > 1 also accumulates the submap clouds on a
    /// background thread while the next scan is processed (the same clouds, bit for bit).
    int num_threads = 2;
    [[nodiscard]] Status Validate() const;
  };

  static StatusOr<std::unique_ptr<Localizer>> Create(const Options& options,
                                                     const Eigen::Isometry3d& T_body_lidar);
  ~Localizer();
  Localizer(const Localizer&) = delete;
  Localizer& operator=(const Localizer&) = delete;

  /// Sets the pose of the first scan (world) before the first ProcessScan; default identity.
  void SetInitialPose(const Eigen::Isometry3d& T_world_body);

  /// Runs the stages above on one raw scan. InvalidArgument for an empty scan or a bad motion input
  /// (nothing is changed then).
  StatusOr<LocalizationResult> ProcessScan(const Scan& scan, const ScanMotionInput& motion);

  /// Submaps so far (the last one may be unfinished). The host (MappingSystem) moves them with
  /// SetSubmapPose to level 2's estimates.
  const std::vector<SubmapRecord>& submaps() const override;
  /// Moves submap `id` to T_world_submap (after a level-2 solve): its surfels follow.
  Status SetSubmapPose(int32_t id, const Eigen::Isometry3d& T_world_submap);
  /// Frees the point clouds of submaps that level 2 no longer needs (memory bound).
  void ReleaseSubmapClouds(int32_t id, bool keep_registration_cloud);
  /// A submap's map or registration cloud (submap frame), from memory or read back from its spill
  /// file. NotFound for an unknown id; DataLoss / NotFound naming the file when the spill file is
  /// unreadable or corrupt.
  StatusOr<PointCloud> SubmapCloud(int32_t id, CloudKind kind) const override;
  /// The same; `stamps` (may be null) gets the map cloud's MapPointStamps (empty for
  /// kRegistration).
  StatusOr<PointCloud> SubmapCloud(int32_t id, CloudKind kind, MapPointStamps* stamps) const;
  /// The private spill folder (empty without Options::spill_dir).
  const std::filesystem::path& spill_folder() const;
  /// Ends the current submap (Finish()).
  void FinishCurrentSubmap();
  /// The live surfel map (the current and the previous submap when per_submap_surfels).
  const SurfelMap& surfel_map() const;
  /// Every surfel: the live map's and the archived ones, at the submaps' current poses.
  std::vector<Surfel> AllSurfels() const;
  const Options& options() const;

 private:
  Localizer();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
