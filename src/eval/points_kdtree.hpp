#pragma once
// Private helper of the eval module: a nanoflann k-d tree over a vector of float points (the map
// entropy's and the scan statistics' neighbourhoods).
//
// Thread safety: a built tree may be searched concurrently; the points must outlive it.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <nanoflann.hpp>
#include <vector>

namespace slam_mms::eval::internal {

// nanoflann dataset adaptor over a vector of float points.
struct PointsAdaptor {
  const std::vector<Eigen::Vector3f>& points;
  size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(uint32_t idx, size_t dim) const { return points[idx][dim]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox& /*bb*/) const {
    return false;
  }
};

using KdTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PointsAdaptor>,
                                        PointsAdaptor, 3, uint32_t>;

}  // namespace slam_mms::eval::internal
