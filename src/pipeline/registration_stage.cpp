#include "pipeline/registration_stage.hpp"

#include <string>
#include <utility>

#include "pipeline/pose_covariance.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms::internal {

StatusOr<RegistrationStage> RegistrationStage::Create(const Localizer::Options& options,
                                                      const RangeProjection& projection,
                                                      const Eigen::Isometry3d& T_body_lidar) {
  RegistrationStage stage;
  stage.dynamic_options_ = options.dynamic;
  stage.min_inlier_ratio_ = options.min_inlier_ratio;
  stage.reg_cov_scale_ = options.reg_cov_scale;
  stage.reg_sigma_floor_rot_rad_ = options.reg_sigma_floor_rot_rad;
  stage.reg_sigma_floor_trans_m_ = options.reg_sigma_floor_trans_m;
  stage.T_body_lidar_ = T_body_lidar;
  stage.T_lidar_body_ = T_body_lidar.inverse();
  ProjectiveIcp::Options icp;
  static_cast<ProjectiveIcpOptions&>(icp) = options.icp;
  icp.num_threads = options.num_threads;
  SLAM_MMS_ASSIGN_OR_RETURN(stage.icp_, ProjectiveIcp::Create(projection, icp));
  stage.dynamic_ = DynamicObjectFilter(options.dynamic, projection, options.icp.max_distance,
                                       options.icp.max_angle_deg);
  return stage;
}

void RegistrationStage::FilterMovingObjects(const VertexNormalMap& model, DeskewedScan* scan,
                                            SurfelMap* map, const ScanStep& step,
                                            LocalizationResult* res) {
  // Moving objects (DynamicObjectOptions), judged at the prediction where it comes from the POS
  // or the IMU. A constant-velocity prediction (LiDAR only, a submap's second scan) is not good
  // enough to judge by, nor is a registration that moving objects may have pulled.
  const MotionFactorType factor = step.pred.factor;
  if (!dynamic_options_.enabled ||
      (factor != MotionFactorType::kOdometry && factor != MotionFactorType::kPreintegration)) {
    return;
  }
  const Eigen::Matrix3d R_submap_lidar = step.pred.T_submap.linear() * T_body_lidar_.linear();
  const Eigen::Vector3f up_lidar =
      (-(R_submap_lidar.transpose() * step.g_submap).normalized()).cast<float>();
  if (!up_lidar.allFinite()) return;
  const DynamicObjectStats st =
      dynamic_.Detect(scan->vnm, model, up_lidar, map->surfels(),
                      travel_.StampBefore(dynamic_options_.max_model_travel_m));
  if (st.num_moving > 0) {
    dynamic_.Apply(&scan->vnm);
    map->RemoveSurfels(dynamic_.seen_through());
    dynamic_.MaskPoints(&scan->cloud);
  }
  res->num_moving_objects = st.num_moving;
  res->num_moving_pixels = st.num_masked_pixels;
}

Status RegistrationStage::Register(const Scan& raw, const VertexNormalMap& model,
                                   DeskewedScan* scan, SurfelMap* map, ScanStep* step,
                                   LocalizationResult* res) {
  step->T_submap_reg.reset();
  return Align(raw, model, Eigen::Isometry3d::Identity(), scan, map, step, res);
}

Status RegistrationStage::Reregister(const Scan& raw, const VertexNormalMap& model,
                                     const Eigen::Isometry3d& T_lidar_pred_lidar,
                                     DeskewedScan* scan, ScanStep* step, LocalizationResult* res) {
  step->T_submap_reg.reset();
  return Align(raw, model, T_lidar_pred_lidar, scan, /*map=*/nullptr, step, res);
}

Status RegistrationStage::Align(const Scan& raw, const VertexNormalMap& model,
                                const Eigen::Isometry3d& T_lidar_pred_lidar, DeskewedScan* scan,
                                SurfelMap* map, ScanStep* step, LocalizationResult* res) {
  const auto t0 = Clock::now();
  if (step->have_model && !step->is_reference) {
    if (map != nullptr) FilterMovingObjects(model, scan, map, *step, res);
    auto reg = icp_.Align(scan->vnm, model, T_lidar_pred_lidar);
    if (!reg.ok()) return reg.status().WithContext("Localizer: scan " + std::to_string(raw.index));
    const RegistrationResult& r = *reg;
    res->registered = true;
    res->termination = r.termination;
    res->num_inliers = r.num_inliers;
    res->inlier_ratio = r.inlier_ratio;
    res->rms_residual_m = r.rms_residual_m;
    res->icp_iterations = r.iterations;
    res->degenerate = r.degeneracy.degenerate;
    res->degeneracy_axis_information = r.degeneracy.axis_information;
    if (r.IsUsable() && r.inlier_ratio >= min_inlier_ratio_ &&
        r.T_target_source.matrix().allFinite()) {
      const Eigen::Isometry3d T_world_body =
          step->T_world_lidar_pred * r.T_target_source * T_lidar_body_;
      step->T_submap_reg = step->T_world_submap.inverse() * T_world_body;
      // Right perturbation of T_world_lidar -> of T_world_body: Ad(T_body_lidar).
      const Matrix6d Ad = se3::Adjoint(T_body_lidar_);
      Matrix6d& cov_reg = step->cov_reg;
      cov_reg = reg_cov_scale_ * (Ad * r.covariance * Ad.transpose());
      cov_reg.diagonal() +=
          DiagonalPoseCovariance(reg_sigma_floor_rot_rad_, reg_sigma_floor_trans_m_).diagonal();
      cov_reg = 0.5 * (cov_reg + cov_reg.transpose()).eval();
    }
  }
  res->timings.register_ms += MsSince(t0);
  return OkStatus();
}

void RegistrationStage::RecordPose(int64_t stamp_ns, const Eigen::Vector3d& p_world) {
  travel_.Add(stamp_ns, p_world, dynamic_options_.max_model_travel_m);
}

}  // namespace slam_mms::internal
