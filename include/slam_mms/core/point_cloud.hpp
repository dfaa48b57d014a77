#pragma once
// PointCloud: the library's own point container (structure of arrays: positions, intensities,
// per-point time offsets), and PointCloudView: a borrowed, strided view so a host's own point type
// can be passed in without a copy.
//
// Ownership: PointCloud owns its arrays. PointCloudView borrows the caller's memory, which must
// outlive every call it is passed to (the library never keeps a view beyond the call). Thread
// safety: value type; concurrent const access is safe.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace slam_mms {

/// A borrowed, strided view of a host's points. Strides are in bytes between consecutive points.
/// `intensity` and `dt_from_scan_start_s` are optional (nullptr: absent).
struct PointCloudView {
  const float* xyz =
      nullptr;  ///< Points x, y, z (float32, consecutive floats) in the sensor frame.
  size_t size = 0;
  size_t stride_bytes = 3 * sizeof(float);
  const float* intensity = nullptr;
  size_t intensity_stride_bytes = sizeof(float);
  const float* dt_from_scan_start_s = nullptr;  ///< Per-point time offset from scan start [s].
  size_t time_stride_bytes = sizeof(float);

  Eigen::Vector3f Point(size_t i) const {
    const auto* p =
        reinterpret_cast<const float*>(reinterpret_cast<const uint8_t*>(xyz) + i * stride_bytes);
    return {p[0], p[1], p[2]};
  }
  float Intensity(size_t i) const {
    return intensity == nullptr
               ? 0.0f
               : *reinterpret_cast<const float*>(reinterpret_cast<const uint8_t*>(intensity) +
                                                 i * intensity_stride_bytes);
  }
  float TimeOffset(size_t i) const {
    return dt_from_scan_start_s == nullptr
               ? 0.0f
               : *reinterpret_cast<const float*>(
                     reinterpret_cast<const uint8_t*>(dt_from_scan_start_s) +
                     i * time_stride_bytes);
  }
};

class PointCloud {
 public:
  PointCloud() = default;

  size_t size() const { return points_.size(); }
  bool empty() const { return points_.empty(); }
  void reserve(size_t n);
  void clear();
  void resize(size_t n);

  /// Appends one point. Intensity is the sensor's reflectance (KITTI: [0, 1]).
  void Add(const Eigen::Vector3f& p, float intensity = 0.0f, float dt_from_scan_start_s = 0.0f);

  /// Copies the points of a host's view (NaN/Inf points are kept: call RemoveNonFinite()).
  static PointCloud FromView(const PointCloudView& view);
  /// A view onto this cloud's arrays (valid until the cloud is modified).
  PointCloudView View() const;

  /// Removes points with any non-finite coordinate; returns how many were removed.
  size_t RemoveNonFinite();

  const std::vector<Eigen::Vector3f>& points() const { return points_; }
  std::vector<Eigen::Vector3f>& points() { return points_; }
  const std::vector<float>& intensities() const { return intensities_; }
  std::vector<float>& intensities() { return intensities_; }
  /// Per-point time offsets from the scan's start [s]; all 0 where unknown.
  const std::vector<float>& time_offsets_s() const { return time_offsets_s_; }
  std::vector<float>& time_offsets_s() { return time_offsets_s_; }

 private:
  std::vector<Eigen::Vector3f> points_;
  std::vector<float> intensities_;
  std::vector<float> time_offsets_s_;
};

}  // namespace slam_mms
