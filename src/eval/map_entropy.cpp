#include "slam_mms/eval/map_entropy.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <string>
#include <thread>
#include <vector>

#include "slam_mms/eval/voxel_downsample.hpp"

namespace slam_mms::eval {
namespace {

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
    if (dist_sq < radius_sq_) {
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
    return true;
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
  float radius_sq_;
  Eigen::Vector3f query_;
  const std::vector<Eigen::Vector3f>& points_;
  size_t n_ = 0;
  Eigen::Vector3d s_ = Eigen::Vector3d::Zero();
  double xx_ = 0, xy_ = 0, xz_ = 0, yy_ = 0, yz_ = 0, zz_ = 0;
};

struct ChunkSums {
  double entropy = 0.0;
  double plane_variance = 0.0;
  double neighbors = 0.0;
  size_t valid = 0;
  size_t sparse = 0;
  size_t degenerate = 0;
};

}  // namespace

Status MapEntropyOptions::Validate() const {
  if (!(radius_m > 0.0) || !std::isfinite(radius_m)) {
    return InvalidArgumentError("MapEntropyOptions::radius_m = " + std::to_string(radius_m) +
                                "; must be finite and > 0");
  }
  if (!(voxel_size_m >= 0.0) || !std::isfinite(voxel_size_m)) {
    return InvalidArgumentError("MapEntropyOptions::voxel_size_m = " +
                                std::to_string(voxel_size_m) + "; must be >= 0 (0 disables it)");
  }
  if (min_neighbors < 4) {
    return InvalidArgumentError(
        "MapEntropyOptions::min_neighbors = " + std::to_string(min_neighbors) +
        "; must be >= 4 (fewer points cannot span a 3-D covariance)");
  }
  if (num_threads < 0) {
    return InvalidArgumentError("MapEntropyOptions::num_threads = " + std::to_string(num_threads) +
                                "; must be >= 0 (0 = all hardware threads)");
  }
  return OkStatus();
}

StatusOr<MapEntropyResult> ComputeMapEntropy(const PointCloudView& map,
                                             const MapEntropyOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  MapEntropyResult result;
  result.options = options;

  std::vector<Eigen::Vector3f> points;
  if (options.voxel_size_m > 0.0) {
    SLAM_MMS_ASSIGN_OR_RETURN(PointCloud down, VoxelDownsample(map, options.voxel_size_m));
    points = std::move(down.points());
  } else {
    points.reserve(map.size);
    for (size_t i = 0; i < map.size; ++i) {
      const Eigen::Vector3f p = map.Point(i);
      if (p.allFinite()) points.push_back(p);
    }
  }
  for (size_t i = 0; i < map.size; ++i) result.num_input_points += map.Point(i).allFinite() ? 1 : 0;
  result.num_evaluated_points = points.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (points.empty()) {
    result.mean_map_entropy = nan;
    result.mean_plane_variance_m2 = nan;
    return result;
  }
  if (points.size() > std::numeric_limits<uint32_t>::max()) {
    return InvalidArgumentError("ComputeMapEntropy: " + std::to_string(points.size()) +
                                " points; at most 2^32 - 1 are supported");
  }

  const PointsAdaptor adaptor{points};
  const KdTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  const float radius_sq = static_cast<float>(options.radius_m * options.radius_m);
  // 3 ln(2 pi e): h = 0.5 (3 ln(2 pi e) + ln det Sigma)   (eq 26).
  const double k3_ln_2pie = 3.0 * std::log(2.0 * M_PI * M_E);

  constexpr size_t kChunk = 4096;
  const size_t num_chunks = (points.size() + kChunk - 1) / kChunk;
  std::vector<ChunkSums> chunks(num_chunks);
  std::atomic<size_t> next_chunk{0};
  const size_t min_n = static_cast<size_t>(options.min_neighbors);

  auto worker = [&]() {
    const nanoflann::SearchParams params(32, 0.0f, /*sorted=*/false);
    for (size_t c = next_chunk++; c < num_chunks; c = next_chunk++) {
      ChunkSums& sums = chunks[c];
      const size_t end = std::min(points.size(), (c + 1) * kChunk);
      for (size_t i = c * kChunk; i < end; ++i) {
        MomentAccumulator acc(radius_sq, points[i], points);
        tree.radiusSearchCustomCallback(points[i].data(), acc, params);
        if (acc.size() < min_n) {
          ++sums.sparse;
          continue;
        }
        const Eigen::Matrix3d cov = acc.Covariance();
        const double det = cov.determinant();
        if (!(det > 0.0) || !std::isfinite(det)) {
          ++sums.degenerate;
          continue;
        }
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
        eig.computeDirect(cov, Eigen::EigenvaluesOnly);
        sums.entropy += 0.5 * (k3_ln_2pie + std::log(det));
        sums.plane_variance += std::max(0.0, eig.eigenvalues()(0));  // ascending order
        sums.neighbors += static_cast<double>(acc.size());
        ++sums.valid;
      }
    }
  };

  size_t threads = options.num_threads == 0 ? std::max(1u, std::thread::hardware_concurrency())
                                            : static_cast<size_t>(options.num_threads);
  threads = std::min(threads, num_chunks);
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();

  // Sum in chunk order: the result does not depend on the thread count or scheduling.
  ChunkSums total;
  for (const ChunkSums& c : chunks) {
    total.entropy += c.entropy;
    total.plane_variance += c.plane_variance;
    total.neighbors += c.neighbors;
    total.valid += c.valid;
    total.sparse += c.sparse;
    total.degenerate += c.degenerate;
  }
  result.num_valid_points = total.valid;
  result.num_sparse_points = total.sparse;
  result.num_degenerate_points = total.degenerate;
  if (total.valid == 0) {
    result.mean_map_entropy = nan;
    result.mean_plane_variance_m2 = nan;
    result.mean_neighbors = 0.0;
  } else {
    const double n = static_cast<double>(total.valid);
    result.mean_map_entropy = total.entropy / n;
    result.mean_plane_variance_m2 = total.plane_variance / n;
    result.mean_neighbors = total.neighbors / n;
  }
  return result;
}

StatusOr<MapEntropyResult> ComputeMapEntropy(const PointCloud& map,
                                             const MapEntropyOptions& options) {
  return ComputeMapEntropy(map.View(), options);
}

}  // namespace slam_mms::eval
