#include "slam_mms/core/point_cloud.hpp"

#include <cmath>

namespace slam_mms {

void PointCloud::reserve(size_t n) {
  points_.reserve(n);
  intensities_.reserve(n);
  time_offsets_s_.reserve(n);
}

void PointCloud::clear() {
  points_.clear();
  intensities_.clear();
  time_offsets_s_.clear();
}

void PointCloud::resize(size_t n) {
  points_.resize(n, Eigen::Vector3f::Zero());
  intensities_.resize(n, 0.0f);
  time_offsets_s_.resize(n, 0.0f);
}

void PointCloud::Add(const Eigen::Vector3f& p, float intensity, float dt_from_scan_start_s) {
  points_.push_back(p);
  intensities_.push_back(intensity);
  time_offsets_s_.push_back(dt_from_scan_start_s);
}

PointCloud PointCloud::FromView(const PointCloudView& view) {
  PointCloud cloud;
  cloud.reserve(view.size);
  for (size_t i = 0; i < view.size; ++i) {
    cloud.Add(view.Point(i), view.Intensity(i), view.TimeOffset(i));
  }
  return cloud;
}

PointCloudView PointCloud::View() const {
  PointCloudView v;
  v.size = points_.size();
  v.xyz = points_.empty() ? nullptr : points_.front().data();
  v.stride_bytes = sizeof(Eigen::Vector3f);
  v.intensity = intensities_.empty() ? nullptr : intensities_.data();
  v.dt_from_scan_start_s = time_offsets_s_.empty() ? nullptr : time_offsets_s_.data();
  return v;
}

size_t PointCloud::RemoveNonFinite() {
  size_t out = 0;
  for (size_t i = 0; i < points_.size(); ++i) {
    if (!points_[i].allFinite()) continue;
    points_[out] = points_[i];
    intensities_[out] = intensities_[i];
    time_offsets_s_[out] = time_offsets_s_[i];
    ++out;
  }
  const size_t removed = points_.size() - out;
  resize(out);
  return removed;
}

}  // namespace slam_mms
