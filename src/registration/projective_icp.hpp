#pragma once
// ProjectiveIcp: frame-to-model point-to-plane ICP with projective data association (paper §5.1.2,
// eq 15; SuMa's Frame2Model, Behley & Stachniss 2018).
//
// The model (the surfel map rendered ONCE at the predicted pose, a VertexNormalMap in the model's
// sensor frame) stays fixed; at every iteration each scan vertex v_s (with normal n_s, scan sensor
// frame) is moved with the current estimate T = T_model_scan, q = T v_s, re-projected with the
// spherical model of the RangeProjection into the model image, and associated with the pixel
// (v_m, n_m) it lands in (nearest pixel). The association is re-checked every iteration:
//   |q - v_m| <= Options::max_distance  and  n_m . (R n_s) >= cos(Options::max_angle_deg).
// Then, eq 15:  E = sum rho( n_m . (T v_s - v_m) )^2  with rho = Huber(Options::huber_delta),
// minimised by Gauss-Newton on SE(3) with the right perturbation T <- T * Exp(delta),
// delta = [omega; v]; J = [ (v_s x R^T n_m)^T, (R^T n_m)^T ].
// The result's T_target_source is T_model_scan; with the model rendered at T_world_model, the scan
// pose is T_world_scan = T_world_model * T_model_scan.
//
// Work is split over Options::num_threads persistent threads; no allocation per iteration (scratch
// buffers are kept across calls, so after the first scan of a given size Align does not allocate).
//
// Ownership: Align borrows both maps for the call only. Move-only.
// Thread safety: not thread-safe; use one ProjectiveIcp per thread.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>

#include "slam_mms/core/status.hpp"
#include "slam_mms/registration/registration_options.hpp"
#include "slam_mms/registration/registration_result.hpp"
#include "slam_mms/surfel/range_projection.hpp"
#include "slam_mms/surfel/vertex_normal_map.hpp"

namespace slam_mms {

class ProjectiveIcp {
 public:
  /// The SDK's options (ProjectiveIcpOptions) plus the thread count its owner sets.
  struct Options : ProjectiveIcpOptions {
    /// Total threads including the caller, in [1, 256].
    int num_threads = 2;
    [[nodiscard]] Status Validate() const;
  };

  /// Default options and the HDL-64 default projection (64 x 2048, +3/-25 deg).
  ProjectiveIcp();
  /// `projection` must be the one the model image was rendered with.
  static StatusOr<ProjectiveIcp> Create(const RangeProjection& projection, const Options& options);
  ~ProjectiveIcp();
  ProjectiveIcp(ProjectiveIcp&&) noexcept;
  ProjectiveIcp& operator=(ProjectiveIcp&&) noexcept;
  ProjectiveIcp(const ProjectiveIcp&) = delete;
  ProjectiveIcp& operator=(const ProjectiveIcp&) = delete;

  const Options& options() const;

  /// Registers the scan's vertex/normal map (scan sensor frame; any size) to the model image
  /// (rows x cols of the projection, model sensor frame), starting from T_model_scan_init.
  /// InvalidArgument if the model's size differs from the projection's or a map's arrays are
  /// inconsistent; estimator outcomes are fields of the result.
  StatusOr<RegistrationResult> Align(const VertexNormalMap& scan, const VertexNormalMap& model,
                                     const Eigen::Isometry3d& T_model_scan_init);

 private:
  struct Impl;
  explicit ProjectiveIcp(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
