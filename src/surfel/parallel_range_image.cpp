#include "surfel/parallel_range_image.hpp"

#include <cstddef>

namespace slam_mms::internal {

void ParallelRangeImage::ComputeVertexNormalMap(const RangeProjection& projection,
                                                const PointCloudView& cloud, VertexNormalMap* out) {
  const RangeProjectionOptions& o = projection.options();
  out->Reset(o.rows, o.cols);
  const size_t n = cloud.size;
  pixel_.resize(n);
  range_.resize(n);
  pool_.Run([&](int ti) {
    size_t i0 = 0;
    size_t i1 = 0;
    pool_.Range(ti, n, &i0, &i1);
    ProjectedPoint px;
    for (size_t i = i0; i < i1; ++i) {
      const Eigen::Vector3f p = cloud.Point(i);
      if (!p.allFinite() || !projection.Project(p, &px)) {
        pixel_[i] = -1;
        continue;
      }
      pixel_[i] = out->PixelIndex(px.row, px.col);
      range_[i] = px.range;
    }
  });
  // As RangeProjection::ComputeVertexMap, in cloud order.
  for (size_t i = 0; i < n; ++i) {
    const int32_t k = pixel_[i];
    if (k < 0) continue;
    float& r = out->range[static_cast<size_t>(k)];
    if (r > 0.0f && r <= range_[i]) continue;  // nearest point wins
    r = range_[i];
    out->vertex[static_cast<size_t>(k)] = cloud.Point(i);
    out->index[static_cast<size_t>(k)] = static_cast<int32_t>(i);
  }
  pool_.Run([&](int ti) {
    size_t r0 = 0;
    size_t r1 = 0;
    pool_.Range(ti, static_cast<size_t>(o.rows), &r0, &r1);
    projection.ComputeNormals(out, static_cast<int>(r0), static_cast<int>(r1));
  });
}

}  // namespace slam_mms::internal
