#pragma once
// DynamicObjectFilter: level 1's moving-object filter (see DynamicObjectOptions for the method).
// It cuts a scan's range image into objects, judges each against the surfel model rendered for
// the same sensor pose, and reports the moving ones as a pixel mask, the model surfels they were
// seen through, and the scan points that fall in their pixels.
//
// Why by hand: no Debian package segments range images or judges them against a rendered model
// (PCL's Euclidean clustering works on unordered clouds, at ~100x the cost of a pass over the
// image).
//
// Thread safety: one filter per thread (scratch buffers are reused across scans).

#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <utility>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/pipeline/dynamic_object_options.hpp"
#include "slam_mms/surfel/range_projection.hpp"
#include "slam_mms/surfel/surfel.hpp"
#include "slam_mms/surfel/vertex_normal_map.hpp"

namespace slam_mms::internal {

/// What one Detect found.
struct DynamicObjectStats {
  int num_objects = 0;        ///< Objects judged (enough pixels with a model correspondence).
  int num_moving = 0;         ///< Of those, moving.
  int num_masked_pixels = 0;  ///< Pixels of the moving objects.
  float threshold_m = 0.0f;   ///< The residual threshold used.
};

/// The vehicle's path length by scan stamp, as far back as the filter needs it.
class TravelHistory {
 public:
  /// Appends a scan's position (world); keeps what lies within keep_m of travel and one more.
  void Add(int64_t stamp_ns, const Eigen::Vector3d& p_world, double keep_m);
  /// The latest stamp at least `travel_m` of travel before the last one added; INT64_MIN when the
  /// history is shorter than that (everything is recent).
  int64_t StampBefore(double travel_m) const;

 private:
  std::deque<std::pair<int64_t, double>> stamps_;  // stamp, cumulative length
  Eigen::Vector3d last_ = Eigen::Vector3d::Zero();
  double length_ = 0.0;
};

class DynamicObjectFilter {
 public:
  DynamicObjectFilter() = default;
  DynamicObjectFilter(const DynamicObjectOptions& options, const RangeProjection& projection,
                      double max_correspondence_m, double max_angle_deg);

  /// Judges `scan` (sensor frame) against `model`, rendered for the same sensor pose (pixel i of
  /// one faces pixel i of the other). `up_scan`: the world's up direction in the
  /// scan's frame. Correspondences beyond the registration's gates (max_correspondence_m, normals
  /// more than max_angle_deg apart) are not used: what the registration ignores cannot pull it.
  /// Only model pixels whose surfel (model.index into `surfels`) was created at or after
  /// min_created_ns are used: older parts of the map have drifted against the scan with the
  /// vehicle's travel, and that is what registration corrects, not motion.
  DynamicObjectStats Detect(const VertexNormalMap& scan, const VertexNormalMap& model,
                            const Eigen::Vector3f& up_scan, const std::vector<Surfel>& surfels,
                            int64_t min_created_ns);

  /// Per scan pixel: 1 where a moving object was found by the last Detect.
  const std::vector<uint8_t>& mask() const { return mask_; }
  /// Model surfel ids (model.index) the moving objects were seen through (scan behind the model
  /// by more than the threshold): the object's old place.
  const std::vector<uint32_t>& seen_through() const { return seen_through_; }

  /// Invalidates the masked pixels of `scan` (no vertex, normal or index).
  void Apply(VertexNormalMap* scan) const;
  /// Sets the points of `cloud` (sensor frame, as projected into the scan image) that fall in a
  /// masked pixel to NaN (index-aligned arrays keep their size). Returns how many.
  size_t MaskPoints(PointCloud* cloud) const;

 private:
  void Segment(const VertexNormalMap& scan, const Eigen::Vector3f& up_scan);

  DynamicObjectOptions options_;
  RangeProjection projection_;
  float max_correspondence_m_ = 2.0f;
  float max_sin_ = 0.5f;
  std::vector<int32_t> label_;  // object per pixel; -1: none
  std::vector<int32_t> queue_;
  int num_labels_ = 0;
  std::vector<float> residual_;       // per pixel; NaN: no correspondence
  std::vector<float> all_residuals_;  // the finite ones, for the robust scale
  std::vector<int8_t> moving_;        // per object
  std::vector<std::vector<float>> object_residuals_;
  std::vector<uint8_t> mask_;
  std::vector<uint32_t> seen_through_;
};

}  // namespace slam_mms::internal
