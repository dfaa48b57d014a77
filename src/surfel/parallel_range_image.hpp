#pragma once
// ParallelRangeImage: RangeProjection::ComputeVertexNormalMap with its per-point projection (two
// inverse trigonometric functions a point) and its normals split over a WorkerPool. The image is
// the same bits as the serial one: the points are projected in parallel into per-point pixel
// records, then written into the image in cloud order by one thread (nearest wins, the earlier
// point on a tie, as in ComputeVertexMap), and the normal rows are independent. Private to the
// library.

#include <cstdint>
#include <vector>

#include "core/worker_pool.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/surfel/range_projection.hpp"
#include "slam_mms/surfel/vertex_normal_map.hpp"

namespace slam_mms::internal {

class ParallelRangeImage {
 public:
  /// `num_threads` >= 1 counts the calling thread (WorkerPool); not thread-safe.
  explicit ParallelRangeImage(int num_threads) : pool_(num_threads) {}

  void ComputeVertexNormalMap(const RangeProjection& projection, const PointCloudView& cloud,
                              VertexNormalMap* out);

 private:
  WorkerPool pool_;
  std::vector<int32_t> pixel_;  ///< Per point: its pixel, or -1 (not projected).
  std::vector<float> range_;    ///< Per point: its range where projected.
};

}  // namespace slam_mms::internal
