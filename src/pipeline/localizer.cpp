#include "slam_mms/pipeline/localizer.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "core/option_error.hpp"
#include "pipeline/localizer_impl.hpp"
#include "pipeline/surfel_renderer_factory.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

SurfelMapOptions DefaultLevel1SurfelOptions() {
  SurfelMapOptions o;
  o.renderer.projection.cols = 1024;
  return o;
}

Status Level1Options::Validate() const {
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
  if (!(registration_voxel_m > 0.0)) {
    return bad("registration_voxel_m", registration_voxel_m, "must be > 0");
  }
  // One field decides what Integrate fuses into (issue #19): per_submap_surfels.
  if (surfels.integrate_current_submap_only) {
    return bad("surfels.integrate_current_submap_only", 1.0,
               "must be false: a Localizer sets it from per_submap_surfels");
  }
  SLAM_MMS_RETURN_IF_ERROR(surfels.Validate());
  SLAM_MMS_RETURN_IF_ERROR(icp.Validate());
  SLAM_MMS_RETURN_IF_ERROR(window.Validate());
  SLAM_MMS_RETURN_IF_ERROR(deskew.Validate());
  SLAM_MMS_RETURN_IF_ERROR(dynamic.Validate());
  SLAM_MMS_RETURN_IF_ERROR(imu.Validate());
  return OkStatus();
}

Status Localizer::Options::Validate() const {
  auto bad = [](const char* field, double v, const char* rule) {
    return internal::OptionError("Localizer::Options", field, v, rule);
  };
  if (!(map_voxel_m > 0.0)) return bad("map_voxel_m", map_voxel_m, "must be > 0");
  if (!(map_max_range_m > 0.0)) return bad("map_max_range_m", map_max_range_m, "must be > 0");
  if (num_threads < 1 || num_threads > 64)
    return bad("num_threads", num_threads, "must be in [1, 64]");
  if (mode == MappingMode::kGnssIns || mode == MappingMode::kGnssInsSmoothed) {
    return InvalidArgumentError(std::string("Localizer::Options::mode = ") + MappingModeName(mode) +
                                "; the Localizer runs only in full or lidar_only mode");
  }
  return Level1Options::Validate();
}

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
  m.motion_prior = internal::MotionPrior(options.imu, options.mode == MappingMode::kFull);
  SLAM_MMS_ASSIGN_OR_RETURN(m.projection,
                            RangeProjection::Create(options.surfels.renderer.projection));
  const int threads = options.num_threads;
  SLAM_MMS_ASSIGN_OR_RETURN(m.deskew,
                            internal::DeskewStage::Create(options, m.projection, T_body_lidar));
  SurfelMapOptions surfel_options = options.surfels;
  surfel_options.integrate_current_submap_only = options.per_submap_surfels;
  SLAM_MMS_ASSIGN_OR_RETURN(m.map, SurfelMap::Create(surfel_options, threads));
  auto renderer = MakeSurfelRenderer(options.surfels.renderer, options.renderer, threads);
  if (!renderer.ok()) return renderer.status().WithContext("Localizer renderer");
  m.renderer = std::move(renderer).value();
  SLAM_MMS_RETURN_IF_ERROR(m.map.SetRenderer(m.renderer.get()));
  m.model = internal::ModelRenderStage(options, T_body_lidar);
  SLAM_MMS_ASSIGN_OR_RETURN(
      m.registration, internal::RegistrationStage::Create(options, m.projection, T_body_lidar));
  m.window = internal::WindowStage(options);
  SLAM_MMS_ASSIGN_OR_RETURN(m.integration,
                            internal::IntegrationStage::Create(options, T_body_lidar));
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
  SLAM_MMS_RETURN_IF_ERROR(m.CheckScan(scan, motion));
  LocalizationResult res;
  res.scan_index = scan.index;
  res.stamp = scan.stamp_start;
  if (!m.started) {
    // The first scan starts submap 0: it must not fail after that (nothing would be undone).
    SLAM_MMS_RETURN_IF_ERROR(ScanDeskewer::CheckTimeOffsets(scan));
    SLAM_MMS_RETURN_IF_ERROR(m.StartFirstSubmap(scan, motion));
  }
  ScanStep step = m.BeginScan(scan, motion);
  // 2. predict first: the preintegration de-skew starts from the prediction.
  m.PredictStage(scan, motion, &step, &res);
  // 1. de-skew
  SLAM_MMS_RETURN_IF_ERROR(
      m.deskew.Deskew(scan, motion, m.motion_prior, m.prev.bias, &step, &m.deskewed, &res));
  // 3. render the model at the prediction
  SLAM_MMS_RETURN_IF_ERROR(m.model.Render(scan, m.current(), m.num_processed, &m.map, &step, &res));
  // 4. register (eq 15), moving objects masked out first
  SLAM_MMS_RETURN_IF_ERROR(
      m.registration.Register(scan, m.model.model(), &m.deskewed, &m.map, &step, &res));
  // 4b. a constant-velocity de-skew refined from the registration (LiDAR only)
  SLAM_MMS_RETURN_IF_ERROR(m.RefineConstantVelocityDeskew(scan, &step, &res));
  // 5. add factors (F_Odom / F_Prein / CV, F_Reg eq 16), 6. optimize the window
  SLAM_MMS_RETURN_IF_ERROR(m.window.AddFactors(scan, motion, m.prev, &step, &res));
  SLAM_MMS_RETURN_IF_ERROR(m.window.Optimize(scan, &step, &m.prev, &res));
  // 7. integrate into the surfel map and the submap's clouds
  SLAM_MMS_RETURN_IF_ERROR(m.integration.Integrate(scan, m.deskewed, step, &m.map, &res));
  m.RecordScan(scan, motion, step, &res);
  // The submap cut every WT: this scan becomes the next submap's reference.
  if (m.integration.CutDue(scan, step)) {
    SLAM_MMS_RETURN_IF_ERROR(m.CutSubmap(scan, step, &res));
  } else if (step.is_reference) {
    res.new_submap = true;
  }
  res.timings.total_ms = MsSince(t_total);
  return res;
}

const std::vector<SubmapRecord>& Localizer::submaps() const {
  return impl_->integration.store().submaps();
}

Status Localizer::SetSubmapPose(int32_t id, const Eigen::Isometry3d& T_world_submap) {
  if (!T_world_submap.matrix().allFinite()) {
    return InvalidArgumentError("Localizer::SetSubmapPose: non-finite pose for submap " +
                                std::to_string(id));
  }
  return impl_->integration.SetSubmapPose(id, T_world_submap, &impl_->map);
}

void Localizer::ReleaseSubmapClouds(int32_t id, bool keep_registration_cloud) {
  impl_->integration.store().ReleaseClouds(id, keep_registration_cloud);
}

StatusOr<PointCloud> Localizer::SubmapCloud(int32_t id, CloudKind kind) const {
  return impl_->integration.store().SubmapCloud(id, kind);
}

StatusOr<PointCloud> Localizer::SubmapCloud(int32_t id, CloudKind kind,
                                            MapPointStamps* stamps) const {
  return impl_->integration.store().SubmapCloud(id, kind, stamps);
}

const std::filesystem::path& Localizer::spill_folder() const {
  return impl_->integration.store().spill_folder();
}

void Localizer::FinishCurrentSubmap() { impl_->integration.CloseCurrentSubmap(); }

const SurfelMap& Localizer::surfel_map() const { return impl_->map; }

std::vector<Surfel> Localizer::AllSurfels() const {
  std::vector<Surfel> all;
  for (const auto& [id, surfels] : impl_->integration.archived_surfels()) {
    all.insert(all.end(), surfels.begin(), surfels.end());
  }
  std::vector<Surfel> live = impl_->map.LiveSurfels();
  all.insert(all.end(), live.begin(), live.end());
  return all;
}
const Localizer::Options& Localizer::options() const { return impl_->opt; }

}  // namespace slam_mms
