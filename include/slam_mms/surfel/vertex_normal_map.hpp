#pragma once
// VertexNormalMap: the range-image record both a scan (RangeProjection::ComputeVertexNormalMap) and
// a rendered surfel model (SurfelRenderer::Render) produce, so projective ICP reads both the same
// way.
//
// Layout: rows x cols, ROW-MAJOR, pixel i = row * cols + col. Row 0 is the TOP row (highest
// elevation, the RangeProjectionOptions::fov_up_deg edge); column 0 is straight behind the sensor
// turning left (see RangeProjection for the exact mapping). All geometry is in the SENSOR frame of
// the pose the image was made for.
//
// Per pixel:
//   - vertex: the 3D point [m] (scan: the nearest point falling in the pixel; model: the
//   intersection
//     of the pixel's centre ray with the nearest surfel disc). (0,0,0) where there is none.
//   - normal: unit normal pointing TOWARDS the sensor (n . vertex < 0); (0,0,0) where there is
//   none.
//   - range: |vertex| [m]; 0 where there is no vertex (HasVertex tests this).
//   - index: scan: the point's index in the input cloud; model: the surfel id (SurfelMap id, or the
//     position in the renderer's input when no ids are given); -1 where there is no vertex.
// A pixel may have a vertex without a normal (a scan pixel whose neighbours are missing or lie
// across a depth discontinuity); a model pixel always has both.
//
// Thread safety: value type; concurrent const access is safe.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace slam_mms {

struct VertexNormalMap {
  int rows = 0;
  int cols = 0;
  std::vector<Eigen::Vector3f> vertex;  ///< Sensor-frame point [m]; zero where invalid.
  std::vector<Eigen::Vector3f> normal;  ///< Unit normal towards the sensor; zero where none.
  std::vector<float> range;             ///< |vertex| [m]; 0 where invalid.
  std::vector<int32_t> index;  ///< Point index (scan) or surfel id (model); -1 where invalid.

  /// Sets the size and marks every pixel invalid. Reuses the existing capacity (no allocation when
  /// the size does not grow), so a map kept across frames does not allocate per frame.
  void Reset(int new_rows, int new_cols);
  /// Marks every pixel invalid, keeping the size.
  void Clear();

  int size() const { return rows * cols; }
  int PixelIndex(int row, int col) const { return row * cols + col; }
  bool HasVertex(int i) const { return range[static_cast<size_t>(i)] > 0.0f; }
  bool HasNormal(int i) const { return normal[static_cast<size_t>(i)].squaredNorm() > 0.5f; }
  /// Number of pixels with a vertex / with a vertex and a normal.
  int CountVertices() const;
  int CountNormals() const;
};

}  // namespace slam_mms
