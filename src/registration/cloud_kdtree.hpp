#pragma once
// A nanoflann k-d tree over a std::vector<Eigen::Vector3f> (no copy of the points), shared by the
// point-to-plane ICP and the extrinsic calibration. Private to the library (src/).
//
// Thread safety: a built tree may be searched concurrently; the points must outlive it and not
// change while it exists.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <nanoflann.hpp>
#include <vector>

namespace slam_mms::registration_internal {

struct CloudAdaptor {
  const std::vector<Eigen::Vector3f>* pts = nullptr;
  size_t kdtree_get_point_count() const { return pts->size(); }
  float kdtree_get_pt(size_t i, size_t d) const { return (*pts)[i][static_cast<int>(d)]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox& /*bb*/) const {
    return false;
  }
};

using CloudKdTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<float, CloudAdaptor, float, uint32_t>, CloudAdaptor, 3, uint32_t>;

}  // namespace slam_mms::registration_internal
