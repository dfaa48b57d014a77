#include "slam_mms/pipeline/localizer.hpp"

#include <ceres/normal_prior.h>

#include <algorithm>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <chrono>
#include <cmath>
#include <deque>
#include <map>
#include <string>
#include <system_error>

#include "backend/imu_preintegration_factor.hpp"
#include "core/option_error.hpp"
#include "pipeline/cloud_file.hpp"
#include "pipeline/pose_covariance.hpp"
#include "pipeline/submap_cloud_builder.hpp"
#include "pipeline/submap_store.hpp"
#include "pipeline/surfel_renderer_factory.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "surfel/parallel_range_image.hpp"

namespace slam_mms {
namespace {

using Clock = std::chrono::steady_clock;

/// Scan intervals over which LiDAR-only mode measures the velocity it de-skews with.
constexpr size_t kDeskewVelocityIntervals = 3;
double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// Pose T scaled along its twist: Exp(s * Log(T)).
Eigen::Isometry3d ScalePose(const Eigen::Isometry3d& T, double s) {
  return se3::Exp(s * se3::Log(T));
}

/// A prior x ~ N(mean, sigma^2 I) on a block of size N, as a ceres::NormalPrior.
std::unique_ptr<ceres::CostFunction> MakeNormalPrior(const Eigen::VectorXd& mean,
                                                     const Eigen::VectorXd& sigma) {
  ceres::Matrix A = ceres::Matrix::Zero(mean.size(), mean.size());
  for (int i = 0; i < mean.size(); ++i) A(i, i) = 1.0 / sigma[i];
  ceres::Vector b = mean;
  return std::make_unique<ceres::NormalPrior>(A, b);
}

}  // namespace

SurfelMapOptions Localizer::DefaultSurfelOptions() {
  SurfelMapOptions o;
  o.renderer.projection.cols = 1024;
  return o;
}

Status Localizer::Options::Validate() const {
  auto bad = [](const char* field, double v, const char* rule) {
    return internal::OptionError("Localizer::Options", field, v, rule);
  };
  if (!(submap_duration_s > 0.0)) return bad("submap_duration_s", submap_duration_s, "must be > 0");
  if (!(model_radius_m > 0.0)) return bad("model_radius_m", model_radius_m, "must be > 0");
  if (!std::isfinite(min_model_confidence)) {
    return bad("min_model_confidence", min_model_confidence, "must be finite");
  }
  if (!(previous_submap_model_s >= 0.0)) {
    return bad("previous_submap_model_s", previous_submap_model_s, "must be >= 0");
  }
  if (!(odom_sigma_rot_rad > 0.0))
    return bad("odom_sigma_rot_rad", odom_sigma_rot_rad, "must be > 0");
  if (!(odom_sigma_trans_m > 0.0))
    return bad("odom_sigma_trans_m", odom_sigma_trans_m, "must be > 0");
  if (!(cv_sigma_rot_rad > 0.0)) return bad("cv_sigma_rot_rad", cv_sigma_rot_rad, "must be > 0");
  if (!(cv_sigma_trans_m > 0.0)) return bad("cv_sigma_trans_m", cv_sigma_trans_m, "must be > 0");
  if (!(reg_cov_scale > 0.0)) return bad("reg_cov_scale", reg_cov_scale, "must be > 0");
  if (!(reg_sigma_floor_rot_rad > 0.0)) {
    return bad("reg_sigma_floor_rot_rad", reg_sigma_floor_rot_rad, "must be > 0");
  }
  if (!(reg_sigma_floor_trans_m > 0.0)) {
    return bad("reg_sigma_floor_trans_m", reg_sigma_floor_trans_m, "must be > 0");
  }
  if (!(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0)) {
    return bad("min_inlier_ratio", min_inlier_ratio, "must be in [0, 1]");
  }
  if (!(map_voxel_m > 0.0)) return bad("map_voxel_m", map_voxel_m, "must be > 0");
  if (!(map_max_range_m > 0.0)) return bad("map_max_range_m", map_max_range_m, "must be > 0");
  if (!(registration_voxel_m > 0.0)) {
    return bad("registration_voxel_m", registration_voxel_m, "must be > 0");
  }
  if (num_threads < 1) return bad("num_threads", num_threads, "must be >= 1");
  if (mode == MappingMode::kGnssIns || mode == MappingMode::kGnssInsSmoothed) {
    return InvalidArgumentError(std::string("Localizer::Options::mode = ") + MappingModeName(mode) +
                                "; the Localizer runs only in full or lidar_only mode");
  }
  SLAM_MMS_RETURN_IF_ERROR(surfels.Validate());
  SLAM_MMS_RETURN_IF_ERROR(icp.Validate());
  SLAM_MMS_RETURN_IF_ERROR(window.Validate());
  SLAM_MMS_RETURN_IF_ERROR(deskew.Validate());
  SLAM_MMS_RETURN_IF_ERROR(imu.Validate());
  return OkStatus();
}

/// What ProcessScan predicts for a scan before registering it.
struct Prediction {
  Eigen::Isometry3d T_submap = Eigen::Isometry3d::Identity();  ///< T_submap_body.
  Eigen::Vector3d v_submap = Eigen::Vector3d::Zero();          ///< Body velocity in the submap.
  MotionFactorType factor = MotionFactorType::kNone;           ///< The motion factor to add.
  std::optional<ImuPreintegration> pre;  ///< F_Prein's preintegration (kPreintegration).
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
  Timestamp prev_stamp;
  Eigen::Isometry3d T_submap_prev = Eigen::Isometry3d::Identity();
  int64_t num_processed = 0;
  /// The last optimized poses (oldest first, the newest is the previous scan's), in the current
  /// submap's frame: the constant-velocity motion of LiDAR-only mode is taken from them.
  std::deque<std::pair<Timestamp, Eigen::Isometry3d>> recent;
  bool has_pos_prev = false;
  Eigen::Isometry3d pos_prev_start = Eigen::Isometry3d::Identity();
  Eigen::Vector3d v_submap_prev = Eigen::Vector3d::Zero();
  Vector6d bias_prev = Vector6d::Zero();

  // Scratch, reused across scans.
  PointCloud deskewed;
  VertexNormalMap scan_vnm;
  VertexNormalMap model_vnm;
  std::vector<uint32_t> active_ids;
  std::vector<uint32_t> model_ids;

  SubmapRecord& current() { return store.current(); }

  Status StartWindow(const Eigen::Vector3d& v_submap, const Vector6d& bias) {
    auto w = SlidingWindowGraph::Create(opt.window);
    if (!w.ok()) return w.status();
    window = std::make_unique<SlidingWindowGraph>(std::move(w).value());
    ref_id = next_id++;
    StateInit init;
    init.keep = true;
    if (use_imu_states) {
      init.v_frame = v_submap;
      init.imu_bias = bias;
    }
    SLAM_MMS_RETURN_IF_ERROR(window->AddState(ref_id, init));
    SLAM_MMS_RETURN_IF_ERROR(window->SetBlockConstant({ref_id, StateBlock::kPose}, true));
    if (use_imu_states) {
      // The reference's velocity and biases carry over from the previous window (or the POS).
      auto v_prior = MakeNormalPrior(v_submap, Eigen::Vector3d::Constant(0.1));
      Eigen::VectorXd b_sigma(6);
      b_sigma << Eigen::Vector3d::Constant(0.05), Eigen::Vector3d::Constant(1e-3);
      auto b_prior = MakeNormalPrior(bias, b_sigma);
      SLAM_MMS_RETURN_IF_ERROR(
          window->AddCostFunction(std::move(v_prior), {{ref_id, StateBlock::kVelocity}}).status());
      SLAM_MMS_RETURN_IF_ERROR(
          window->AddCostFunction(std::move(b_prior), {{ref_id, StateBlock::kBias}}).status());
    }
    prev_id = ref_id;
    return OkStatus();
  }

  void StartSubmap(const Eigen::Isometry3d& T_world_submap, Timestamp stamp, int64_t scan_index,
                   const Eigen::Isometry3d& T_prev_this, const Matrix6d& cov_prev_this) {
    const int32_t id =
        store.Start(T_world_submap, stamp, scan_index, T_prev_this, cov_prev_this).id;
    map.SetSubmapId(id);
    if (opt.per_submap_surfels) RetireOldSurfels(id);
    clouds->Clear();
  }

  /// Takes the surfels of submaps older than current_id - 1 out of the live map (archiving the
  /// stable ones when asked).
  void RetireOldSurfels(int32_t current_id) {
    removed_scratch.clear();
    map.RemoveSubmapsExcept({current_id, current_id - 1},
                            opt.archive_surfels ? &removed_scratch : nullptr);
    const float threshold = static_cast<float>(opt.surfels.confidence_threshold);
    for (const Surfel& s : removed_scratch) {
      if (s.confidence > threshold) archived_surfels[s.submap_id].push_back(s);
    }
    removed_scratch.clear();
  }

  void CloseCurrentSubmap() {
    if (store.empty() || store.current().finished) return;
    internal::SubmapCloudBuilder::Clouds built = clouds->Build();
    MapPointStamps stamps;
    stamps.time_ns = std::move(built.time_ns);
    stamps.scan_index = std::move(built.scan_index);
    store.FinishCurrent(std::move(built.map), std::move(stamps), std::move(built.registration));
    clouds->Clear();
#if defined(__GLIBC__)
    // A submap's clouds, grids and sort buffers (tens of MB) were just freed; glibc keeps such
    // blocks in its heaps, where later small allocations fragment them and the process's RSS
    // grows along the drive (measured: 420 MiB after 5 min of driving, 333 MiB with large
    // blocks returned at once). Returning the free pages once per submap keeps it flat.
    malloc_trim(0);
#endif
  }

  /// Step 2 of ProcessScan: the pose and velocity predicted for `scan` from the previous one and
  /// the motion factor that will tie them (F_Odom only where the previous scan had a POS pose).
  Prediction Predict(const Scan& scan, const ScanMotionInput& motion, bool is_reference,
                     const Eigen::Isometry3d& T_world_submap,
                     const Eigen::Vector3d& g_submap) const {
    Prediction out;
    out.T_submap = T_submap_prev;
    out.v_submap = v_submap_prev;
    out.factor = is_reference ? MotionFactorType::kNone : motion.type;
    if (!is_reference) {
      const double dt = scan.stamp_start.SecondsSince(prev_stamp);
      if (out.factor == MotionFactorType::kOdometry && !has_pos_prev) {
        out.factor = use_imu_states && !motion.imu.empty() ? MotionFactorType::kPreintegration
                                                           : MotionFactorType::kConstantVelocity;
      }
      if (out.factor == MotionFactorType::kOdometry) {
        out.T_submap = T_submap_prev * (pos_prev_start.inverse() * motion.T_world_body_pos_start);
        out.v_submap = T_world_submap.linear().transpose() * motion.v_world_pos;
      } else if (out.factor == MotionFactorType::kPreintegration) {
        ImuPreintegration pre(opt.imu, bias_prev.head<3>(), bias_prev.tail<3>());
        const Status st = pre.IntegrateWindow(motion.imu, prev_stamp, scan.stamp_start);
        if (st.ok() && pre.num_samples() > 0) {
          NavState s;
          s.q_world_body = Eigen::Quaterniond(T_submap_prev.linear());
          s.p_world = T_submap_prev.translation();
          s.v_world = v_submap_prev;
          const NavState e = pre.Predict(s, g_submap);
          out.T_submap = MakeIsometry(e.q_world_body, e.p_world);
          out.v_submap = e.v_world;
          out.pre = std::move(pre);
        } else {
          SLAM_MMS_LOG(kWarning) << "Localizer: scan " << scan.index
                                 << ": IMU does not cover the scan interval (" << st.message()
                                 << "); constant-velocity prediction instead";
          out.factor = MotionFactorType::kConstantVelocity;
        }
      }
      if (out.factor == MotionFactorType::kConstantVelocity) {
        // The prediction follows the last interval (it tracks acceleration; registration corrects
        // it, so it does not feed back like the de-skew).
        if (auto motion_cv = ConstantVelocityMotion(dt, 1))
          out.T_submap = T_submap_prev * *motion_cv;
      }
    }
    return out;
  }

  /// Step 5 of ProcessScan, the motion factor between the previous scan's state and `cur_state`:
  /// F_Odom (eq 12), F_Prein (eq 14) or the constant-velocity factor. Returns its covariance (the
  /// registration's consistency check uses it).
  StatusOr<Matrix6d> AddMotionFactor(StateId cur_state, const ScanMotionInput& motion,
                                     const Prediction& pred, double dt,
                                     const Eigen::Isometry3d& T_world_submap,
                                     const Eigen::Vector3d& g_submap) {
    Matrix6d cov_motion =
        internal::DiagonalPoseCovariance(opt.cv_sigma_rot_rad, opt.cv_sigma_trans_m);
    if (pred.factor == MotionFactorType::kOdometry) {
      // F_Odom (eq 12) between consecutive scans: the POS relative motion.
      cov_motion = internal::DiagonalPoseCovariance(opt.odom_sigma_rot_rad, opt.odom_sigma_trans_m);
      SLAM_MMS_RETURN_IF_ERROR(
          window
              ->AddRelativePoseFactor(prev_id, cur_state,
                                      pos_prev_start.inverse() * motion.T_world_body_pos_start,
                                      cov_motion, FactorKind::kMotion)
              .status());
      if (use_imu_states) {
        const Eigen::Vector3d v_submap = T_world_submap.linear().transpose() * motion.v_world_pos;
        SLAM_MMS_RETURN_IF_ERROR(
            window
                ->AddCostFunction(MakeNormalPrior(v_submap, Eigen::Vector3d::Constant(0.05)),
                                  {{cur_state, StateBlock::kVelocity}})
                .status());
        Eigen::VectorXd b_sigma(6);
        b_sigma << Eigen::Vector3d::Constant(0.05), Eigen::Vector3d::Constant(1e-3);
        SLAM_MMS_RETURN_IF_ERROR(window
                                     ->AddCostFunction(MakeNormalPrior(motion.pos_bias, b_sigma),
                                                       {{cur_state, StateBlock::kBias}})
                                     .status());
      }
    } else if (pred.factor == MotionFactorType::kPreintegration) {
      // F_Prein (eq 14) with bias random walk between consecutive scans.
      auto factor = ImuPreintegrationFactor::Create(*pred.pre, g_submap);
      if (!factor.ok()) return factor.status().WithContext("Localizer: preintegration factor");
      SLAM_MMS_RETURN_IF_ERROR(
          window
              ->AddCostFunction(std::move(factor).value(), {{prev_id, StateBlock::kPose},
                                                            {prev_id, StateBlock::kVelocity},
                                                            {prev_id, StateBlock::kBias},
                                                            {cur_state, StateBlock::kPose},
                                                            {cur_state, StateBlock::kVelocity},
                                                            {cur_state, StateBlock::kBias}})
              .status());
      cov_motion = internal::DiagonalPoseCovariance(0.002 + 0.001 * dt, 0.02 + 0.05 * dt);
    } else {
      // LiDAR only: a weak constant-velocity factor keeps degenerate directions bounded.
      cov_motion = internal::DiagonalPoseCovariance(opt.cv_sigma_rot_rad, opt.cv_sigma_trans_m);
      SLAM_MMS_RETURN_IF_ERROR(
          window
              ->AddRelativePoseFactor(prev_id, cur_state, T_submap_prev.inverse() * pred.T_submap,
                                      cov_motion, FactorKind::kMotion, RobustLoss::Huber(3.0))
              .status());
    }
    return cov_motion;
  }

  /// The submap cut every WT (end of ProcessScan): `scan`, at T_submap_cur in the current submap,
  /// becomes the reference of a new submap; the level-1 state is re-expressed in it.
  Status CutSubmap(const Scan& scan, const Eigen::Isometry3d& T_world_submap,
                   const Eigen::Isometry3d& T_submap_cur, LocalizationResult* res) {
    const Eigen::Isometry3d T_prev_this = T_submap_cur;
    const Matrix6d cov_prev_this = res->cov_T_world_body;
    // The scan belongs to the new submap (it is its reference), not to the old one.
    SubmapRecord& old = current();
    old.scan_indices.pop_back();
    old.scan_stamps.pop_back();
    old.T_submap_scan.pop_back();
    old.cov_submap_scan.pop_back();
    old.end = old.scan_stamps.back();
    CloseCurrentSubmap();
    StartSubmap(T_world_submap * T_submap_cur, scan.stamp_start, scan.index, T_prev_this,
                cov_prev_this);
    // Re-express the level-1 state in the new frame.
    const Eigen::Isometry3d T_new_old = T_submap_cur.inverse();
    for (auto& [stamp, T] : recent) T = T_new_old * T;
    T_submap_prev = Eigen::Isometry3d::Identity();
    v_submap_prev = T_submap_cur.linear().transpose() * v_submap_prev;
    SLAM_MMS_RETURN_IF_ERROR(StartWindow(v_submap_prev, bias_prev));
    clouds->Add(deskewed, scan.cloud.time_offsets_s(), scan.stamp_start.nanoseconds(), scan.index,
                T_body_lidar, opt.map_max_range_m);
    res->new_submap = true;
    res->submap_id = current().id;
    SLAM_MMS_LOG(kDebug) << "Localizer: submap " << current().id << " starts at scan "
                         << scan.index;
    return OkStatus();
  }

  /// Body motion over `duration` seconds at the mean velocity of the last `intervals` scan
  /// intervals (fewer at the start); nullopt before two scans.
  std::optional<Eigen::Isometry3d> ConstantVelocityMotion(double duration, size_t intervals) const {
    if (recent.size() < 2) return std::nullopt;
    const size_t first = recent.size() - 1 - std::min(intervals, recent.size() - 1);
    const auto& [t0, T0] = recent[first];
    const auto& [t1, T1] = recent.back();
    const double dt = t1.SecondsSince(t0);
    if (!(dt > 1e-3)) return std::nullopt;
    return ScalePose(T0.inverse() * T1, duration / dt);
  }

  /// De-skew motion over the scan, T_bstart_bend, by the motion source.
  Eigen::Isometry3d DeskewMotion(const Scan& scan, const ScanMotionInput& motion,
                                 const Eigen::Isometry3d& T_submap_pred,
                                 const Eigen::Vector3d& v_submap_pred,
                                 const Eigen::Vector3d& g_submap) const {
    const double duration = scan.DurationSeconds();
    switch (motion.type) {
      case MotionFactorType::kOdometry:
        return motion.T_world_body_pos_start.inverse() * motion.T_world_body_pos_end;
      case MotionFactorType::kPreintegration: {
        ImuPreintegration pre(opt.imu, bias_prev.head<3>(), bias_prev.tail<3>());
        if (pre.IntegrateWindow(motion.imu, scan.stamp_start, scan.stamp_end).ok() &&
            pre.num_samples() > 0) {
          NavState s;
          s.q_world_body = Eigen::Quaterniond(T_submap_pred.linear());
          s.p_world = T_submap_pred.translation();
          s.v_world = v_submap_pred;
          const NavState e = pre.Predict(s, g_submap);
          Eigen::Isometry3d T_end = MakeIsometry(e.q_world_body, e.p_world);
          return T_submap_pred.inverse() * T_end;
        }
        [[fallthrough]];
      }
      default:
        // The velocity over several scan intervals, not the last one: with the last interval, an
        // error in the estimated rotation between two scans bends the next de-skewed scan, whose
        // registration then errs the other way, and the alternating error grows (measured on the
        // simulated drive: 40 deg of roll error after 8 s). Averaging over
        // kDeskewVelocityIntervals intervals cancels that alternating mode.
        return ConstantVelocityMotion(duration, kDeskewVelocityIntervals)
            .value_or(Eigen::Isometry3d::Identity());
    }
  }
};

Localizer::Localizer() : impl_(std::make_unique<Impl>()) {}
Localizer::~Localizer() = default;

StatusOr<std::unique_ptr<Localizer>> Localizer::Create(const Options& options,
                                                       const Eigen::Isometry3d& T_body_lidar) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (!T_body_lidar.matrix().allFinite()) {
    return InvalidArgumentError("Localizer: T_body_lidar is not finite");
  }
  std::unique_ptr<Localizer> loc(new Localizer());
  Impl& m = *loc->impl_;
  m.opt = options;
  m.T_body_lidar = T_body_lidar;
  m.T_lidar_body = T_body_lidar.inverse();
  m.use_imu_states = options.mode == MappingMode::kFull;
  SLAM_MMS_ASSIGN_OR_RETURN(m.projection,
                            RangeProjection::Create(options.surfels.renderer.projection));
  SLAM_MMS_ASSIGN_OR_RETURN(m.deskewer, ScanDeskewer::Create(options.deskew));
  SurfelMapOptions surfel_options = options.surfels;
  if (options.per_submap_surfels) surfel_options.integrate_current_submap_only = true;
  SLAM_MMS_ASSIGN_OR_RETURN(m.map, SurfelMap::Create(surfel_options));
  auto renderer = MakeSurfelRenderer(options.surfels.renderer, options.renderer);
  if (!renderer.ok()) return renderer.status().WithContext("Localizer renderer");
  m.renderer = std::move(renderer).value();
  SLAM_MMS_RETURN_IF_ERROR(m.map.SetRenderer(m.renderer.get()));
  SLAM_MMS_ASSIGN_OR_RETURN(m.icp, ProjectiveIcp::Create(m.projection, options.icp));
  m.clouds = std::make_unique<internal::SubmapCloudBuilder>(
      options.map_voxel_m, options.registration_voxel_m, /*asynchronous=*/options.num_threads > 1);
  m.range_image = std::make_unique<internal::ParallelRangeImage>(options.num_threads);
  auto store = internal::SubmapStore::Create(options.spill_dir);
  if (!store.ok()) return store.status().WithContext("Localizer::Options::spill_dir");
  m.store = std::move(store).value();
  SLAM_MMS_LOG(kInfo) << "Localizer: mode " << MappingModeName(options.mode) << ", renderer "
                      << m.renderer->Name() << ", WT " << options.submap_duration_s << " s";
  return loc;
}

void Localizer::SetInitialPose(const Eigen::Isometry3d& T_world_body) {
  impl_->initial_T_world_body = T_world_body;
}

StatusOr<LocalizationResult> Localizer::ProcessScan(const Scan& scan,
                                                    const ScanMotionInput& motion) {
  Impl& m = *impl_;
  const auto t_total = Clock::now();
  if (scan.cloud.empty()) {
    return InvalidArgumentError("Localizer: scan '" + scan.source + "' (index " +
                                std::to_string(scan.index) + ") has no points");
  }
  if (m.started && !(m.prev_stamp < scan.stamp_start)) {
    return InvalidArgumentError("Localizer: scan '" + scan.source + "' starts at " +
                                scan.stamp_start.ToKittiString() +
                                ", not after the previous scan at " + m.prev_stamp.ToKittiString());
  }
  if (motion.type == MotionFactorType::kOdometry &&
      (!motion.T_world_body_pos_start.matrix().allFinite() ||
       !motion.T_world_body_pos_end.matrix().allFinite() || !motion.v_world_pos.allFinite())) {
    return InvalidArgumentError("Localizer: non-finite POS motion for scan '" + scan.source + "'");
  }
  LocalizationResult res;
  res.scan_index = scan.index;
  res.stamp = scan.stamp_start;

  // ---- first scan: it is the reference of submap 0 ---------------------------------------------
  if (!m.started) {
    Eigen::Isometry3d T_world_body0 = m.initial_T_world_body;
    if (motion.type == MotionFactorType::kOdometry) T_world_body0 = motion.T_world_body_pos_start;
    m.StartSubmap(T_world_body0, scan.stamp_start, scan.index, Eigen::Isometry3d::Identity(),
                  Matrix6d::Identity() * 1e-8);
    const Eigen::Vector3d v_submap0 = T_world_body0.linear().transpose() * motion.v_world_pos;
    m.bias_prev = motion.pos_bias;
    SLAM_MMS_RETURN_IF_ERROR(m.StartWindow(v_submap0, m.bias_prev));
    m.started = true;
    m.v_submap_prev = v_submap0;
  }
  const Eigen::Isometry3d T_world_submap = m.current().T_world_submap;
  const Eigen::Vector3d g_submap = T_world_submap.linear().transpose() * motion.g_world;
  const bool is_reference =
      m.current().scan_indices.size() == 1 && m.current().scan_stamps.front() == scan.stamp_start;

  // ---- 2. predict (done first: the preintegration de-skew starts from the prediction) ----------
  auto t0 = Clock::now();
  Prediction pred = m.Predict(scan, motion, is_reference, T_world_submap, g_submap);
  const Eigen::Isometry3d& T_submap_pred = pred.T_submap;
  const Eigen::Vector3d& v_submap_pred = pred.v_submap;
  const MotionFactorType factor_type = pred.factor;
  res.motion_factor = factor_type;
  res.timings.predict_ms = MsSince(t0);

  // ---- 1. de-skew ------------------------------------------------------------------------------
  t0 = Clock::now();
  ScanMotionInput deskew_motion = motion;
  if (factor_type != MotionFactorType::kOdometry &&
      factor_type != MotionFactorType::kPreintegration &&
      motion.type == MotionFactorType::kOdometry) {
    deskew_motion.type = MotionFactorType::kOdometry;  // POS is fine for de-skew even without prev
  }
  const Eigen::Isometry3d T_bstart_bend =
      m.DeskewMotion(scan, deskew_motion, T_submap_pred, v_submap_pred, g_submap);
  SLAM_MMS_RETURN_IF_ERROR(m.deskewer.Deskew(scan, T_bstart_bend, m.T_body_lidar, &m.deskewed));
  m.range_image->ComputeVertexNormalMap(m.projection, m.deskewed.View(), &m.scan_vnm);
  res.timings.deskew_ms = MsSince(t0);

  // ---- 3. render the current and previous submap at the prediction -----------------------------
  t0 = Clock::now();
  const Eigen::Isometry3d T_world_lidar_pred = T_world_submap * T_submap_pred * m.T_body_lidar;
  const int32_t cur_id = m.current().id;
  // SuMa's threshold schedule: all surfels at first, the stable ones after 10 scans.
  constexpr double kInitialThreshold = -2.1972245773362196;  // ln(0.1 / 0.9)
  const double ramp = std::min(1.0, static_cast<double>(m.num_processed) / 10.0);
  const float model_threshold = static_cast<float>(
      kInitialThreshold + ramp * (m.opt.min_model_confidence - kInitialThreshold));
  const bool with_previous =
      scan.stamp_start.SecondsSince(m.current().start) < m.opt.previous_submap_model_s;
  m.map.SelectActive(T_world_lidar_pred.translation(), m.opt.model_radius_m, model_threshold,
                     &m.active_ids);
  m.model_ids.clear();
  const auto& surfels = m.map.surfels();
  for (uint32_t id : m.active_ids) {
    const int32_t sid = surfels[id].submap_id;
    if (sid == cur_id || (with_previous && sid == cur_id - 1)) m.model_ids.push_back(id);
  }
  res.num_model_surfels = m.model_ids.size();
  bool have_model = m.model_ids.size() >= 100;
  if (have_model) {
    SLAM_MMS_RETURN_IF_ERROR(m.renderer->Render(SurfelRenderInput::Subset(surfels, m.model_ids),
                                                T_world_lidar_pred, &m.model_vnm));
  }
  res.timings.render_ms = MsSince(t0);

  // ---- 4. register scan-to-submap (eq 15) ------------------------------------------------------
  t0 = Clock::now();
  std::optional<Eigen::Isometry3d> T_submap_reg;
  Matrix6d cov_reg = Matrix6d::Identity();
  if (have_model && !is_reference) {
    auto reg = m.icp.Align(m.scan_vnm, m.model_vnm, Eigen::Isometry3d::Identity());
    if (!reg.ok()) return reg.status().WithContext("Localizer: scan " + std::to_string(scan.index));
    const RegistrationResult& r = *reg;
    res.registered = true;
    res.termination = r.termination;
    res.num_inliers = r.num_inliers;
    res.inlier_ratio = r.inlier_ratio;
    res.rms_residual_m = r.rms_residual_m;
    res.icp_iterations = r.iterations;
    res.degenerate = r.degeneracy.degenerate;
    res.degeneracy_axis_information = r.degeneracy.axis_information;
    if (r.IsUsable() && r.inlier_ratio >= m.opt.min_inlier_ratio &&
        r.T_target_source.matrix().allFinite()) {
      const Eigen::Isometry3d T_world_body =
          T_world_lidar_pred * r.T_target_source * m.T_lidar_body;
      T_submap_reg = T_world_submap.inverse() * T_world_body;
      // Right perturbation of T_world_lidar -> of T_world_body: Ad(T_body_lidar).
      const Matrix6d Ad = se3::Adjoint(m.T_body_lidar);
      cov_reg = m.opt.reg_cov_scale * (Ad * r.covariance * Ad.transpose());
      cov_reg.diagonal() += internal::DiagonalPoseCovariance(m.opt.reg_sigma_floor_rot_rad,
                                                             m.opt.reg_sigma_floor_trans_m)
                                .diagonal();
      cov_reg = 0.5 * (cov_reg + cov_reg.transpose()).eval();
    }
  }
  res.timings.register_ms = MsSince(t0);

  // ---- 5. add factors
  // ----------------------------------------------------------------------------
  t0 = Clock::now();
  const double dt = is_reference ? 0.0 : scan.stamp_start.SecondsSince(m.prev_stamp);
  StateId cur_state = m.ref_id;
  if (!is_reference) {
    cur_state = m.next_id++;
    StateInit init;
    init.T_frame_body = T_submap_reg.value_or(T_submap_pred);
    if (m.use_imu_states) {
      init.v_frame = v_submap_pred;
      init.imu_bias = m.bias_prev;
    }
    SLAM_MMS_RETURN_IF_ERROR(m.window->AddState(cur_state, init));
    SLAM_MMS_ASSIGN_OR_RETURN(
        const Matrix6d cov_motion,
        m.AddMotionFactor(cur_state, motion, pred, dt, T_world_submap, g_submap));
    if (T_submap_reg) {
      // F_Reg (eq 16): reference -> scan, checked against the motion prediction.
      MotionPrediction prediction;
      prediction.T_a_b = T_submap_pred;
      prediction.covariance = 4.0 * cov_motion + internal::DiagonalPoseCovariance(0.003, 0.05);
      auto outcome = m.window->AddRelativePoseFactor(m.ref_id, cur_state, *T_submap_reg, cov_reg,
                                                     FactorKind::kRegistration,
                                                     RobustLoss::Huber(3.0), prediction);
      if (!outcome.ok()) return outcome.status().WithContext("Localizer: F_Reg");
      res.registration_used = outcome->id.has_value();
      res.registration_downweighted = outcome->covariance_scale > 1.0;
      res.consistency_mahalanobis_sq = outcome->mahalanobis_sq;
      if (!res.registration_used) {
        SLAM_MMS_LOG(kDebug) << "Localizer: scan " << scan.index
                             << ": registration rejected by the consistency check (d2 = "
                             << outcome->mahalanobis_sq << ")";
      }
    }
  }
  res.timings.factors_ms = MsSince(t0);

  // ---- 6. optimize
  // -------------------------------------------------------------------------------
  t0 = Clock::now();
  Eigen::Isometry3d T_submap_cur = Eigen::Isometry3d::Identity();
  if (!is_reference) {
    auto summary = m.window->Solve();
    if (!summary.ok()) return summary.status().WithContext("Localizer: window solve");
    if (!summary->usable()) {
      SLAM_MMS_LOG(kWarning) << "Localizer: scan " << scan.index << ": window solve "
                             << SolveTerminationName(summary->termination) << ": "
                             << summary->message;
    }
    SLAM_MMS_ASSIGN_OR_RETURN(T_submap_cur, m.window->Pose(cur_state));
    if (m.use_imu_states) {
      auto v = m.window->Velocity(cur_state);
      auto b = m.window->ImuBias(cur_state);
      if (v.ok()) m.v_submap_prev = *v;
      if (b.ok()) m.bias_prev = *b;
    }
    auto cov = m.window->PoseCovariance(cur_state);
    res.cov_T_world_body = cov.ok() ? *cov : (T_submap_reg ? cov_reg : 4.0 * Matrix6d::Identity());
  } else {
    res.cov_T_world_body = Matrix6d::Identity() * 1e-8;
  }
  res.timings.optimize_ms = MsSince(t0);

  // ---- 7. integrate the scan's surfels at the optimized pose -----------------------------------
  t0 = Clock::now();
  const Eigen::Isometry3d T_world_lidar = T_world_submap * T_submap_cur * m.T_body_lidar;
  auto stats = m.map.Integrate(m.scan_vnm, T_world_lidar, scan.stamp_start);
  if (!stats.ok()) return stats.status().WithContext("Localizer: surfel integration");
  res.num_surfels = stats->num_surfels;
  const Eigen::Isometry3d T_submap_lidar = T_submap_cur * m.T_body_lidar;
  m.clouds->Add(m.deskewed, scan.cloud.time_offsets_s(), scan.stamp_start.nanoseconds(), scan.index,
                T_submap_lidar, m.opt.map_max_range_m);
  res.timings.integrate_ms = MsSince(t0);

  // ---- bookkeeping ------------------------------------------------------------------------------
  if (!is_reference) {
    SubmapRecord& rec = m.current();
    rec.scan_indices.push_back(scan.index);
    rec.scan_stamps.push_back(scan.stamp_start);
    rec.T_submap_scan.push_back(T_submap_cur);
    rec.cov_submap_scan.push_back(res.cov_T_world_body);
    rec.end = scan.stamp_start;
  }
  res.submap_id = m.current().id;
  res.T_world_body = T_world_submap * T_submap_cur;
  ++m.num_processed;
  m.recent.emplace_back(scan.stamp_start, T_submap_cur);
  while (m.recent.size() > kDeskewVelocityIntervals + 1) m.recent.pop_front();
  m.T_submap_prev = T_submap_cur;
  m.prev_stamp = scan.stamp_start;
  m.prev_id = cur_state;
  m.has_pos_prev = motion.type == MotionFactorType::kOdometry;
  m.pos_prev_start = motion.T_world_body_pos_start;
  if (!m.use_imu_states && motion.type == MotionFactorType::kOdometry) {
    m.v_submap_prev = T_world_submap.linear().transpose() * motion.v_world_pos;
  }

  // ---- submap cut every WT: this scan becomes the next submap's reference -----------------------
  if (!is_reference &&
      scan.stamp_start.SecondsSince(m.current().start) >= m.opt.submap_duration_s) {
    SLAM_MMS_RETURN_IF_ERROR(m.CutSubmap(scan, T_world_submap, T_submap_cur, &res));
  } else if (is_reference) {
    res.new_submap = true;
  }
  res.timings.total_ms = MsSince(t_total);
  return res;
}

const std::vector<SubmapRecord>& Localizer::submaps() const { return impl_->store.submaps(); }

Status Localizer::SetSubmapPose(int32_t id, const Eigen::Isometry3d& T_world_submap) {
  if (!T_world_submap.matrix().allFinite()) {
    return InvalidArgumentError("Localizer::SetSubmapPose: non-finite pose for submap " +
                                std::to_string(id));
  }
  for (const SubmapRecord& rec : impl_->store.submaps()) {
    if (rec.id != id) continue;
    // The surfels follow the submap.
    const Eigen::Isometry3d T_new_old = T_world_submap * rec.T_world_submap.inverse();
    impl_->map.TransformSubmap(id, T_new_old);
    if (auto it = impl_->archived_surfels.find(id); it != impl_->archived_surfels.end()) {
      const Eigen::Matrix3f R = T_new_old.linear().cast<float>();
      const Eigen::Vector3f t = T_new_old.translation().cast<float>();
      for (Surfel& s : it->second) TransformSurfel(R, t, &s);
    }
    break;
  }
  return impl_->store.SetPose(id, T_world_submap);
}

void Localizer::ReleaseSubmapClouds(int32_t id, bool keep_registration_cloud) {
  impl_->store.ReleaseClouds(id, keep_registration_cloud);
}

StatusOr<PointCloud> Localizer::SubmapCloud(int32_t id, CloudKind kind) const {
  return impl_->store.SubmapCloud(id, kind);
}

StatusOr<PointCloud> Localizer::SubmapCloud(int32_t id, CloudKind kind,
                                            MapPointStamps* stamps) const {
  return impl_->store.SubmapCloud(id, kind, stamps);
}

const std::filesystem::path& Localizer::spill_folder() const { return impl_->store.spill_folder(); }

void Localizer::FinishCurrentSubmap() { impl_->CloseCurrentSubmap(); }

const SurfelMap& Localizer::surfel_map() const { return impl_->map; }

std::vector<Surfel> Localizer::AllSurfels() const {
  std::vector<Surfel> all;
  for (const auto& [id, surfels] : impl_->archived_surfels) {
    all.insert(all.end(), surfels.begin(), surfels.end());
  }
  std::vector<Surfel> live = impl_->map.LiveSurfels();
  all.insert(all.end(), live.begin(), live.end());
  return all;
}
const Localizer::Options& Localizer::options() const { return impl_->opt; }

}  // namespace slam_mms
