#include "slam_mms/eval/map_entropy.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/radix_sort.hpp"
#include "core/voxel_grid.hpp"
#include "eval/points_kdtree.hpp"
#include "slam_mms/core/voxel_downsample.hpp"

namespace slam_mms::eval {
namespace {

using internal::KdTree;
using internal::MomentAccumulator;
using internal::PointsAdaptor;

// The points sorted into cubic cells of edge r, with an open-addressing table from cell key to
// the cell's range in the sorted points. A point within r of a query lies in the 3 x 3 x 3 cells
// around the query's cell; the cells of one (x, y) column are consecutive in key order, so the
// block is 9 column ranges, which the query prunes by its horizontal distance to each column
// (conservatively: the neighbours are exactly the k-d tree's). Edge r / 2 with 5 x 5 x 5 blocks
// tests fewer points but was 1.7x slower (hash lookups, more columns).
class NeighbourGrid {
 public:
  struct Column {
    uint32_t begin = 0, end = 0;           // points of the column's cells
    float x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // the column's horizontal box
  };
  static constexpr int kReach = 1;  // cells each side of the query's
  using Block = std::array<Column, (2 * kReach + 1) * (2 * kReach + 1)>;

  NeighbourGrid(const std::vector<Eigen::Vector3f>& points, double radius_m) {
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
    Eigen::Vector3f hi = -lo;
    for (const Eigen::Vector3f& p : points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    // A hair wider than r: a float distance that rounds below r^2 stays inside the block.
    cell_ = radius_m * (1.0 + 1e-4);
    const double inv = 1.0 / cell_;
    for (int a = 0; a < 3; ++a) {
      // kReach + 1 spare cells on each side for the blocks of the border cells.
      if ((static_cast<double>(hi[a]) - lo[a]) * inv + 2 * (kReach + 1) >
          static_cast<double>(kMask)) {
        return;
      }
    }
    // Cells of slam_mms::internal::VoxelGrid with a corner at the lowest point; keys packed
    // relative to kBase (kReach + 1 spare cells below cell 0), which the span check above keeps
    // exact.
    grid_ = slam_mms::internal::VoxelGrid(cell_, lo.cast<double>());
    std::vector<std::pair<uint64_t, uint32_t>> keyed(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      slam_mms::internal::VoxelCell c;
      if (!grid_.CellOf(points[i], &c) ||
          !slam_mms::internal::PackVoxelCell(c, kBase, &keyed[i].first)) {
        return;
      }
      keyed[i].second = static_cast<uint32_t>(i);
    }
    {  // by cell, then by input index (stable, from index order): deterministic
      std::vector<std::pair<uint64_t, uint32_t>> scratch;
      slam_mms::internal::RadixSortByKey(&keyed, &scratch);
    }
    points_.resize(points.size());
    for (int a = 0; a < 3; ++a) axis_[a].resize(points.size());
    for (size_t i = 0; i < keyed.size(); ++i) {
      points_[i] = points[keyed[i].second];
      for (int a = 0; a < 3; ++a) axis_[a][i] = points_[i][a];
      if (i == 0 || keyed[i].first != keyed[i - 1].first) {
        keys_.push_back(keyed[i].first);
        begin_.push_back(static_cast<uint32_t>(i));
      }
    }
    begin_.push_back(static_cast<uint32_t>(points.size()));
    size_t capacity = 16;
    while (capacity < 2 * keys_.size()) capacity *= 2;
    table_.assign(capacity, kNone);
    bits_ = __builtin_ctzll(capacity);
    for (uint32_t c = 0; c < keys_.size(); ++c) {
      size_t slot = Slot(keys_[c]);
      while (table_[slot] != kNone) slot = (slot + 1) & (capacity - 1);
      table_[slot] = c;
    }
    ok_ = true;
  }

  bool ok() const { return ok_; }
  size_t num_cells() const { return keys_.size(); }
  const std::vector<Eigen::Vector3f>& points() const { return points_; }
  /// The sorted points' coordinate `a` (0 = x, 1 = y, 2 = z), for loops the compiler vectorises.
  const float* axis(int a) const { return axis_[a].data(); }
  std::pair<uint32_t, uint32_t> CellRange(size_t cell) const {
    return {begin_[cell], begin_[cell + 1]};
  }
  // The non-empty columns of the block around `cell`; returns how many.
  int Columns(size_t cell, Block* out) const {
    const slam_mms::internal::VoxelCell c = slam_mms::internal::UnpackVoxelCell(keys_[cell], kBase);
    int n = 0;
    for (int32_t x = c.x - kReach; x <= c.x + kReach; ++x) {
      for (int32_t y = c.y - kReach; y <= c.y + kReach; ++y) {
        uint32_t first = kNone, last = kNone;
        for (int32_t z = c.z - kReach; z <= c.z + kReach; ++z) {
          uint64_t key = 0;
          if (!slam_mms::internal::PackVoxelCell({x, y, z}, kBase, &key)) continue;
          const uint32_t found = Find(key);
          if (found == kNone) continue;
          if (first == kNone) first = found;
          last = found;
        }
        if (first == kNone) continue;
        Column& col = (*out)[static_cast<size_t>(n++)];
        col.begin = begin_[first];
        col.end = begin_[last + 1];
        col.x0 = static_cast<float>(grid_.Lower(x, 0));
        col.x1 = static_cast<float>(grid_.Lower(x + 1, 0));
        col.y0 = static_cast<float>(grid_.Lower(y, 1));
        col.y1 = static_cast<float>(grid_.Lower(y + 1, 1));
      }
    }
    return n;
  }

 private:
  static constexpr uint64_t kMask = slam_mms::internal::kVoxelPackSpan - 1;
  static constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
  static constexpr slam_mms::internal::VoxelCell kBase{-(kReach + 1), -(kReach + 1), -(kReach + 1)};

  size_t Slot(uint64_t key) const {
    return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - bits_));
  }
  uint32_t Find(uint64_t key) const {
    const size_t mask = table_.size() - 1;
    for (size_t slot = Slot(key);; slot = (slot + 1) & mask) {
      const uint32_t c = table_[slot];
      if (c == kNone || keys_[c] == key) return c;
    }
  }

  bool ok_ = false;
  double cell_ = 1.0;
  slam_mms::internal::VoxelGrid grid_;
  int bits_ = 4;
  std::vector<Eigen::Vector3f> points_;     // sorted by cell
  std::array<std::vector<float>, 3> axis_;  // the same points, one array per coordinate
  std::vector<uint64_t> keys_;              // per occupied cell, ascending
  std::vector<uint32_t> begin_;             // per cell: first point; one past the last at the end
  std::vector<uint32_t> table_;             // key -> cell, open addressing
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

  const float radius_sq = static_cast<float>(options.radius_m * options.radius_m);
  // 3 ln(2 pi e): h = 0.5 (3 ln(2 pi e) + ln det Sigma)   (eq 26).
  const double k3_ln_2pie = 3.0 * std::log(2.0 * M_PI * M_E);
  const size_t min_n = static_cast<size_t>(options.min_neighbors);
  // One query: its neighbours' moments to the entropy and plane-variance sums.
  auto evaluate = [&](const MomentAccumulator& acc, ChunkSums* sums) {
    if (acc.size() < min_n) {
      ++sums->sparse;
      return;
    }
    const Eigen::Matrix3d cov = acc.Covariance();
    const double det = cov.determinant();
    if (!(det > 0.0) || !std::isfinite(det)) {
      ++sums->degenerate;
      return;
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov, Eigen::EigenvaluesOnly);
    sums->entropy += 0.5 * (k3_ln_2pie + std::log(det));
    sums->plane_variance += std::max(0.0, eig.eigenvalues()(0));  // ascending order
    sums->neighbors += static_cast<double>(acc.size());
    ++sums->valid;
  };

  size_t threads = options.num_threads == 0 ? std::max(1u, std::thread::hardware_concurrency())
                                            : static_cast<size_t>(options.num_threads);
  std::vector<ChunkSums> chunks;
  std::atomic<size_t> next_chunk{0};
  auto run = [&](size_t num_chunks, auto&& chunk_fn) {
    chunks.assign(num_chunks, ChunkSums());
    next_chunk = 0;
    auto worker = [&]() {
      for (size_t c = next_chunk++; c < num_chunks; c = next_chunk++) chunk_fn(c, &chunks[c]);
    };
    const size_t n_threads = std::min(threads, num_chunks);
    std::vector<std::thread> pool;
    for (size_t t = 1; t < n_threads; ++t) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
  };

  const NeighbourGrid grid(points, options.radius_m);
  if (grid.ok()) {
    // Queries in cell order: a cell's queries share its block of columns. A column is skipped
    // when its horizontal box is farther than r from the query (with a margin: the test only
    // skips columns that hold no neighbour), its points tested as the k-d tree tests them.
    const float prune_sq = radius_sq * (1.0f + 1e-3f);
    constexpr size_t kCellsPerChunk = 512;
    // The neighbours of a query are selected without a branch (an index is written for every
    // point tested and kept only where it lies within r: about a third of the tested points are,
    // and the branch mispredicted), then accumulated in the same order as before: the same sums.
    run((grid.num_cells() + kCellsPerChunk - 1) / kCellsPerChunk, [&](size_t c, ChunkSums* sums) {
      NeighbourGrid::Block block;
      std::vector<uint32_t> inside;
      std::vector<float> distances;
      const float* const xs = grid.axis(0);
      const float* const ys = grid.axis(1);
      const float* const zs = grid.axis(2);
      const size_t end = std::min(grid.num_cells(), (c + 1) * kCellsPerChunk);
      const std::vector<Eigen::Vector3f>& pts = grid.points();
      for (size_t cell = c * kCellsPerChunk; cell < end; ++cell) {
        const int num_columns = grid.Columns(cell, &block);
        size_t block_points = 0;
        for (int b = 0; b < num_columns; ++b) {
          block_points += block[static_cast<size_t>(b)].end - block[static_cast<size_t>(b)].begin;
        }
        if (inside.size() < block_points) inside.resize(block_points);
        if (distances.size() < block_points) distances.resize(block_points);
        uint32_t* const selected = inside.data();
        float* const dist_sq = distances.data();
        const auto [q0, q1] = grid.CellRange(cell);
        for (uint32_t q = q0; q < q1; ++q) {
          const Eigen::Vector3f& query = pts[q];
          const float qx = query.x(), qy = query.y(), qz = query.z();
          size_t n = 0;
          for (int b = 0; b < num_columns; ++b) {
            const NeighbourGrid::Column& col = block[static_cast<size_t>(b)];
            const float gap_x = std::max({col.x0 - qx, qx - col.x1, 0.0f});
            const float gap_y = std::max({col.y0 - qy, qy - col.y1, 0.0f});
            if (gap_x * gap_x + gap_y * gap_y > prune_sq) continue;
            // |query - p|^2 as nanoflann's L2_Simple_Adaptor computes it (float, the dimensions in
            // order), so that the grid keeps exactly the neighbours the k-d tree keeps; over
            // coordinate arrays, which the compiler vectorises.
            const uint32_t count = col.end - col.begin;
            const float* px = xs + col.begin;
            const float* py = ys + col.begin;
            const float* pz = zs + col.begin;
            for (uint32_t k = 0; k < count; ++k) {
              const float dx = qx - px[k];
              const float dy = qy - py[k];
              const float dz = qz - pz[k];
              dist_sq[k] = (dx * dx + dy * dy) + dz * dz;
            }
            for (uint32_t k = 0; k < count; ++k) {
              selected[n] = col.begin + k;
              n += dist_sq[k] < radius_sq ? 1 : 0;
            }
          }
          MomentAccumulator acc(radius_sq, query, pts);
          acc.addInside(selected, n);
          evaluate(acc, sums);
        }
      }
    });
  } else {
    // Coordinates beyond the grid's key range: the k-d tree over the points as given.
    const PointsAdaptor adaptor{points};
    const KdTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    constexpr size_t kChunk = 4096;
    run((points.size() + kChunk - 1) / kChunk, [&](size_t c, ChunkSums* sums) {
      const nanoflann::SearchParams params(32, 0.0f, /*sorted=*/false);
      const size_t end = std::min(points.size(), (c + 1) * kChunk);
      for (size_t i = c * kChunk; i < end; ++i) {
        MomentAccumulator acc(radius_sq, points[i], points);
        tree.radiusSearchCustomCallback(points[i].data(), acc, params);
        evaluate(acc, sums);
      }
    });
  }

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
