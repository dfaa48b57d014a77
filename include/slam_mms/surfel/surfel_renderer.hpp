#pragma once
// SurfelRenderer: renders surfels as oriented discs into a model VertexNormalMap seen from a sensor
// pose, with the spherical projection of RangeProjection (paper §5.1.2: the model view that
// projective ICP associates against). Two implementations produce the same images:
// CpuSurfelRenderer (native multithreaded z-buffer splat, module surfel) and EglSurfelRenderer
// (headless OpenGL, module render_egl). MakeSurfelRenderer (module render_egl) chooses between
// them.
//
// The image, exactly (both implementations):
//   A surfel s (map frame) is brought into the sensor frame: p = R p_w + t, n = R n_w
//   (T_sensor_world = T_world_sensor^-1). It is drawn only if
//     min_range_m <= |p| <= max_range_m, radius < |p|, and n . (-p / |p|) > min_facing_cos.
//   For every pixel whose CENTRE RAY d (RangeProjection::RayDirection) hits the disc, i.e.
//     n . d < 0, t = (n . p) / (n . d), |t d - p| <= radius, min_range_m <= t <= max_range_m,
//   the candidate depth is t. Per pixel the smallest t wins; ties go to the surfel drawn first.
//   The pixel then holds vertex = t d (the ray-disc intersection, not the disc centre), range = t,
//   normal = n, index = the surfel's id.
// Surfels are drawn in the order given (ids[0], ids[1], ... or 0, 1, ... without ids).
//
// Thread safety: a renderer is NOT thread-safe (it owns scratch buffers and, for EGL, a GL
// context); use one per thread. Ownership: Render borrows the surfel array only for the call.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/surfel/range_projection.hpp"
#include "slam_mms/surfel/surfel.hpp"
#include "slam_mms/surfel/vertex_normal_map.hpp"

namespace slam_mms {

struct SurfelRendererOptions {
  /// Image size, vertical field of view and range gates of the model image.
  RangeProjectionOptions projection;
  /// Draw a surfel only if its normal faces the sensor: n . (-p/|p|) > min_facing_cos (SuMa: 0.01).
  double min_facing_cos = 0.01;

  [[nodiscard]] Status Validate() const;
};

/// The surfels to draw: surfels[ids[k]] for k < num_ids, or surfels[0..num_surfels) when ids is
/// null.
struct SurfelRenderInput {
  const Surfel* surfels = nullptr;
  size_t num_surfels = 0;
  const uint32_t* ids =
      nullptr;  ///< Optional subset (e.g. SurfelMap::SelectActive); each < num_surfels.
  size_t num_ids = 0;

  static SurfelRenderInput All(const std::vector<Surfel>& s) {
    return {s.data(), s.size(), nullptr, 0};
  }
  static SurfelRenderInput Subset(const std::vector<Surfel>& s, const std::vector<uint32_t>& ids) {
    return {s.data(), s.size(), ids.data(), ids.size()};
  }
  size_t count() const { return ids != nullptr ? num_ids : num_surfels; }
};

class SurfelRenderer {
 public:
  virtual ~SurfelRenderer() = default;

  /// Renders `input` seen from T_world_sensor into `out` (resized to rows x cols; every pixel
  /// written). The index of a pixel is ids[k] (or k without ids). InvalidArgument for an id out of
  /// range or a null array with a non-zero count; Internal/Unavailable for a GL failure.
  [[nodiscard]] virtual Status Render(const SurfelRenderInput& input,
                                      const Eigen::Isometry3d& T_world_sensor,
                                      VertexNormalMap* out) = 0;

  /// "cpu", or "egl (<GL renderer string>)".
  virtual std::string Name() const = 0;
  virtual const RangeProjection& projection() const = 0;
};

/// Checks the input array/ids (shared by the implementations).
[[nodiscard]] Status ValidateRenderInput(const SurfelRenderInput& input);

/// Which renderer a Localizer uses (the choice is made in pipeline's MakeSurfelRenderer):
/// kAuto = EGL on a hardware GPU where the render_egl module is built, else the CPU renderer;
/// kCpu / kEgl = that one.
enum class SurfelRendererBackend { kAuto = 0, kCpu = 1, kEgl = 2 };

}  // namespace slam_mms
