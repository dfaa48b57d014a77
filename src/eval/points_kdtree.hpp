#pragma once
// Private helpers of the eval module: a nanoflann k-d tree over a vector of float points and a
// result set that accumulates the covariance of a radius neighbourhood (the map entropy's and the
// scan statistics' neighbourhoods).
//
// Thread safety: a built tree may be searched concurrently; the points must outlive it.

#include <Eigen/Core>
#include <Eigen/Geometry>
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

// A nanoflann radius-search result set that accumulates the first and second moments of the
// neighbours (relative to the query, in double) instead of storing them.
class MomentAccumulator {
 public:
  MomentAccumulator(float radius_sq, const Eigen::Vector3f& query,
                    const std::vector<Eigen::Vector3f>& points)
      : radius_sq_(radius_sq), query_(query), points_(points) {}

  void init() { clear(); }
  void clear() {
    n_ = 0;
    s_.setZero();
    xx_ = xy_ = xz_ = yy_ = yz_ = zz_ = 0.0;
  }
  size_t size() const { return n_; }
  bool full() const { return true; }
  float worstDist() const { return radius_sq_; }
  bool addPoint(float dist_sq, uint32_t index) {
    if (dist_sq < radius_sq_) Accumulate(index);
    return true;
  }
  /// Adds the points `indices[0..n)`, already known to lie within the radius, in that order: the
  /// same sums as addPoint on each of them.
  void addInside(const uint32_t* indices, size_t n) {
    for (size_t k = 0; k < n; ++k) Accumulate(indices[k]);
  }

  /// Maximum-likelihood covariance (divided by N) of the accumulated neighbours.
  Eigen::Matrix3d Covariance() const {
    const double inv_n = 1.0 / static_cast<double>(n_);
    const Eigen::Vector3d m = s_ * inv_n;
    Eigen::Matrix3d c;
    c << xx_, xy_, xz_, xy_, yy_, yz_, xz_, yz_, zz_;
    c *= inv_n;
    c -= m * m.transpose();
    return c;
  }

 private:
  void Accumulate(uint32_t index) {
    const Eigen::Vector3d d = (points_[index] - query_).cast<double>();
    s_ += d;
    xx_ += d.x() * d.x();
    xy_ += d.x() * d.y();
    xz_ += d.x() * d.z();
    yy_ += d.y() * d.y();
    yz_ += d.y() * d.z();
    zz_ += d.z() * d.z();
    ++n_;
  }

  float radius_sq_;
  Eigen::Vector3f query_;
  const std::vector<Eigen::Vector3f>& points_;
  size_t n_ = 0;
  Eigen::Vector3d s_ = Eigen::Vector3d::Zero();
  double xx_ = 0, xy_ = 0, xz_ = 0, yy_ = 0, yz_ = 0, zz_ = 0;
};

}  // namespace slam_mms::eval::internal
