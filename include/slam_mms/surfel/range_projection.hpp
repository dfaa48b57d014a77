#pragma once
// RangeProjection: the spherical projection of a spinning LiDAR (paper §5.1.2; SuMa, Behley &
// Stachniss 2018), mapping sensor-frame points to range-image pixels and back, and building the
// vertex and normal maps of a (de-skewed) scan.
//
// Pixel coordinates. For p = (x, y, z) in the sensor frame (x forward, y left, z up), r = |p|,
// yaw = atan2(y, x) in (-pi, pi], pitch = asin(z / r), fov = fov_up - fov_down (radians):
//   u (continuous column) = 0.5 * (1 - yaw / pi) * cols       in [0, cols]   (SuMa's convention:
//                                                                  straight ahead at cols / 2, the
//                                                                  left half (+y) at smaller u)
//   v (continuous row)    = (fov_up - pitch) / fov * rows      row 0 = top = fov_up edge
//   col = floor(u) (u == cols wraps to 0), row = floor(v).
// Pixel (row, col) covers [col, col+1) x [row, row+1); its centre is (col + 0.5, row + 0.5). A
// point projects only if 0 <= v < rows and min_range_m <= r <= max_range_m. Unproject(u, v, r)
// inverts the mapping exactly (up to float rounding) for any u, v.
//
// Thread safety: immutable after construction; all const methods may be called concurrently.

#include <Eigen/Core>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/surfel/vertex_normal_map.hpp"

namespace slam_mms {

struct RangeProjectionOptions {
  int rows = 64;                ///< Image height = elevation bins (HDL-64E: 64 beams).
  int cols = 2048;              ///< Image width = azimuth bins (HDL-64E at 10 Hz: ~2000 firings).
  double fov_up_deg = 3.0;      ///< Elevation of the top edge of row 0 [deg] (SuMa: +3).
  double fov_down_deg = -25.0;  ///< Elevation of the bottom edge of the last row [deg] (SuMa: -25).
  double min_range_m = 2.0;     ///< Points nearer than this are dropped [m] (SuMa min_depth 2).
  double max_range_m = 100.0;  ///< Points farther than this are dropped [m] (SuMa model depth 100).
  /// Normal estimation: a neighbour pixel is used only if its range differs from the centre's by at
  /// most max(normal_max_range_jump_m, normal_max_range_jump_ratio * range) (a depth-discontinuity
  /// test that SuMa commented out). Of the left/right and up/down neighbours, the one nearer in
  /// range is used.
  double normal_max_range_jump_m = 0.5;
  double normal_max_range_jump_ratio = 0.15;
  /// Normal estimation: horizontal neighbours are taken normal_col_step columns away (vertical ones
  /// one row away). With 2048 columns adjacent points are only ~3 cm apart at 10 m, so range noise
  /// would dominate a one-column difference.
  int normal_col_step = 2;

  /// Names the first bad field and its rule, e.g. "RangeProjectionOptions::rows = 0; must be > 0".
  [[nodiscard]] Status Validate() const;
};

/// Where a point lands in the range image.
struct ProjectedPoint {
  float u = 0.0f;      ///< Continuous column in [0, cols).
  float v = 0.0f;      ///< Continuous row in [0, rows).
  float range = 0.0f;  ///< |p| [m].
  int col = 0;         ///< floor(u), in [0, cols).
  int row = 0;         ///< floor(v), in [0, rows).
};

class RangeProjection {
 public:
  /// HDL-64E defaults (64 x 2048, +3 / -25 deg, 2..100 m).
  RangeProjection();
  /// Returns InvalidArgument when options.Validate() fails.
  static StatusOr<RangeProjection> Create(const RangeProjectionOptions& options);

  const RangeProjectionOptions& options() const { return options_; }
  int rows() const { return options_.rows; }
  int cols() const { return options_.cols; }

  /// Projects a sensor-frame point. Returns false (and leaves *out unspecified) when the point is
  /// outside the vertical FOV or the range gate, or is not finite.
  bool Project(const Eigen::Vector3f& p_sensor, ProjectedPoint* out) const;
  /// Continuous (u, v) of a direction, ignoring the range gate; false outside the vertical FOV.
  bool ProjectDirection(const Eigen::Vector3f& p_sensor, float* u, float* v) const;
  /// The point at continuous pixel coordinates (u, v) and range r: inverse of Project.
  Eigen::Vector3f Unproject(float u, float v, float range) const;
  /// Unit direction of the ray through the centre of pixel (row, col) (a precomputed table).
  const Eigen::Vector3f& RayDirection(int row, int col) const {
    return ray_directions_[static_cast<size_t>(row * options_.cols + col)];
  }
  /// The whole row-major table of pixel-centre ray directions (rows * cols). Each is exactly
  /// (row_cos[r] * col_cos[c], row_cos[r] * col_sin[c], row_sin[r]) in float arithmetic, so a
  /// renderer may rebuild it from the small per-row/per-column tables below bit for bit.
  const std::vector<Eigen::Vector3f>& ray_directions() const { return ray_directions_; }
  /// cos / sin of the elevation of each row's centre, and of the azimuth of each column's centre.
  const std::vector<float>& row_cos() const { return row_cos_; }
  const std::vector<float>& row_sin() const { return row_sin_; }
  const std::vector<float>& col_cos() const { return col_cos_; }
  const std::vector<float>& col_sin() const { return col_sin_; }

  /// Vertex map of a scan whose points are in the sensor frame (de-skew first): in each pixel the
  /// NEAREST point wins; index = the point's index in `cloud`. Non-finite points are skipped.
  /// `out` is resized with VertexNormalMap::Reset (no allocation when reused).
  void ComputeVertexMap(const PointCloudView& cloud, VertexNormalMap* out) const;
  void ComputeVertexMap(const PointCloud& cloud, VertexNormalMap* out) const {
    ComputeVertexMap(cloud.View(), out);
  }
  /// Fills the normals of a vertex map from neighbouring pixels: n = normalize(dh x dv) where dh is
  /// the difference to the left or right neighbour (wrapping around) and dv to the upper or lower
  /// one, each the neighbour nearer in range that passes the discontinuity test; oriented towards
  /// the sensor. Pixels without two usable neighbours get no normal.
  void ComputeNormals(VertexNormalMap* map) const;
  /// The same for rows [row_begin, row_end) only (other rows are read, not written), so that
  /// callers can split the rows over threads; the result does not depend on the split.
  void ComputeNormals(VertexNormalMap* map, int row_begin, int row_end) const;
  /// ComputeVertexMap followed by ComputeNormals.
  void ComputeVertexNormalMap(const PointCloudView& cloud, VertexNormalMap* out) const;
  void ComputeVertexNormalMap(const PointCloud& cloud, VertexNormalMap* out) const {
    ComputeVertexNormalMap(cloud.View(), out);
  }

 private:
  explicit RangeProjection(const RangeProjectionOptions& options);

  RangeProjectionOptions options_;
  float fov_up_rad_ = 0.0f;
  float fov_rad_ = 0.0f;
  std::vector<Eigen::Vector3f> ray_directions_;
  std::vector<float> row_cos_, row_sin_, col_cos_, col_sin_;
};

}  // namespace slam_mms
