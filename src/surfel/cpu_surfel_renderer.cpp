#include "surfel/cpu_surfel_renderer.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include "core/option_error.hpp"
#include "core/worker_pool.hpp"
#include "surfel/fast_math.hpp"

namespace slam_mms {
namespace {

constexpr uint32_t kNoWinner = std::numeric_limits<uint32_t>::max();

struct DepthWinner {
  float depth;
  uint32_t winner;
};
// Added to the disc's angular radius: covers the ~1e-5 rad error of FastAtan2.
constexpr float kAngleMarginRad = 1e-4f;
// Relative widening of the division-free depth pre-test (>> the few ulps of its rounding).
constexpr float kDepthSlack = 1.0f + 1e-6f;
// Discs subtending less than this [rad] are bounded by their linearised projection.
constexpr float kLinearBoundMaxAngle = 0.1f;

// Lower bound of cos(e) for e in [0, pi/2] (alternating Taylor series cut after a negative term).
inline float CosLowerBound(float e) {
  const float e2 = e * e;
  return 1.0f - e2 * (0.5f - e2 * (1.0f / 24.0f - e2 * (1.0f / 720.0f)));
}

// One disc clipped to one column bin: what the raster pass needs, in the sensor frame.
struct SplatRecord {
  float px, py, pz;  // centre
  float nx, ny, nz;  // normal
  float n_dot_p;
  float r2;    // radius^2
  uint32_t k;  // draw position
  int32_t row0, row1;
  int32_t col0 = 0, col1 = 0;  // wrapped columns, inside the bin, col0 <= col1
};

// Column bins: narrow enough that a bin's depth/winner rows stay in L1/L2 while it is rastered.
constexpr int kBinCols = 128;

// One thread's splat records of a render, per column bin, each bin a list of fixed-size chunks
// taken from one pool that the thread reuses across renders. The pool grows to the most records
// the thread has culled in one render. A vector per bin grew instead to the most records that bin
// ever held, and the sum of those all-time maxima rose along a drive as the scene turned through
// the bins (measured on a 10-minute drive: 98 MiB, most of the process's growth after warm-up).
class BinnedRecords {
 public:
  static constexpr int kChunk = 512;  // records (26 KiB)

  /// Empties every bin (the chunks stay in the pool).
  void Clear(int num_bins) {
    head_.assign(static_cast<size_t>(num_bins), -1);
    tail_.assign(static_cast<size_t>(num_bins), -1);
    used_ = 0;
  }
  void Push(int bin, const SplatRecord& r) {
    int32_t& tail = tail_[static_cast<size_t>(bin)];
    if (tail < 0 || count_[static_cast<size_t>(tail)] == kChunk) {
      const int32_t c = NewChunk();
      if (tail < 0) {
        head_[static_cast<size_t>(bin)] = c;
      } else {
        next_[static_cast<size_t>(tail)] = c;
      }
      tail = c;
    }
    const size_t t = static_cast<size_t>(tail);
    chunks_[t][static_cast<size_t>(count_[t]++)] = r;
  }
  /// Calls f on bin b's records in the order they were pushed.
  template <typename F>
  void ForEach(int b, F&& f) const {
    for (int32_t c = head_[static_cast<size_t>(b)]; c >= 0; c = next_[static_cast<size_t>(c)]) {
      const SplatRecord* chunk = chunks_[static_cast<size_t>(c)].get();
      const int n = count_[static_cast<size_t>(c)];
      for (int i = 0; i < n; ++i) f(chunk[i]);
    }
  }

 private:
  int32_t NewChunk() {
    if (used_ == chunks_.size()) {
      chunks_.push_back(std::make_unique<SplatRecord[]>(kChunk));
      next_.push_back(-1);
      count_.push_back(0);
    }
    next_[used_] = -1;
    count_[used_] = 0;
    return static_cast<int32_t>(used_++);
  }

  std::vector<std::unique_ptr<SplatRecord[]>> chunks_;  // the pool; [0, used_) in use
  std::vector<int32_t> next_;                           // per chunk: the bin's next chunk or -1
  std::vector<int32_t> count_;                          // per chunk: records in it
  std::vector<int32_t> head_, tail_;                    // per bin: first / last chunk or -1
  size_t used_ = 0;
};

}  // namespace

struct CpuSurfelRenderer::Impl {
  Impl(const SurfelRendererOptions& o, int num_threads)
      : options(o),
        projection(*RangeProjection::Create(o.projection)),
        pool(num_threads),
        num_bins((o.projection.cols + kBinCols - 1) / kBinCols),
        records(static_cast<size_t>(num_threads)) {
    depth.resize(static_cast<size_t>(o.projection.rows) * static_cast<size_t>(o.projection.cols));
  }

  // Culls draw positions [k0, k1) and appends their splat records to their bins in `bins`.
  void Cull(const SurfelRenderInput& in, const Eigen::Matrix3f& R, const Eigen::Vector3f& t,
            size_t k0, size_t k1, BinnedRecords* bins) const;
  // Rasters bin b's records (all threads', in draw order) into `depth`.
  void Raster(int b);

  SurfelRendererOptions options;
  RangeProjection projection;
  internal::WorkerPool pool;
  int num_bins;
  // records[thread], reused across calls.
  std::vector<BinnedRecords> records;
  // rows * cols: nearest depth and the draw position of its surfel.
  std::vector<DepthWinner> depth;
  std::atomic<int> next_bin{0};
};

namespace {

// Culling and bounding in blocks: the surfels of a block are gathered into arrays, bounded by one
// branch-free loop that the compiler vectorises (every lane computes both bounds and keeps one by
// a select), then the visible ones are clipped to bins. The arithmetic is the scalar cull's,
// operation for operation (no reassociation, no contraction), so the bounds are the same floats.
constexpr int kCullBlock = 64;

struct CullConstants {
  float R[9];  // row-major
  float t[3];
  float min_r2, max_r2, facing;
  float fov_up, rows_f, rows_per_rad, cols_f, cols_per_rad, inv_pi;
};

struct CullBlockData {
  // In: the surfels (map frame).
  alignas(64) float x[kCullBlock], y[kCullBlock], z[kCullBlock];
  alignas(64) float mx[kCullBlock], my[kCullBlock], mz[kCullBlock], radius[kCullBlock];
  // Out: sensor-frame centre and normal, n.p, r^2, row bounds, column centre and half-width
  // (e_yaw < 0: all columns), visibility.
  alignas(64) float px[kCullBlock], py[kCullBlock], pz[kCullBlock];
  alignas(64) float nx[kCullBlock], ny[kCullBlock], nz[kCullBlock];
  alignas(64) float n_dot_p[kCullBlock], r2[kCullBlock], v_lo[kCullBlock], v_hi[kCullBlock];
  alignas(64) float u[kCullBlock], hu[kCullBlock], e_yaw[kCullBlock];
  alignas(64) int32_t visible[kCullBlock];
};

// The builtins (std:: overloads are calls the vectoriser does not see through); without errno
// (this file is compiled with -fno-math-errno: a negative argument gives NaN either way).
inline float Sqrt(float v) { return __builtin_sqrtf(v); }
inline float Abs(float v) { return __builtin_fabsf(v); }

// std::max / std::min of the scalar cull ((a < b) ? b : a and (b < a) ? b : a).
inline float MaxOf(float a, float b) { return a < b ? b : a; }

void BoundBlock(const CullConstants& c, int n, CullBlockData* b) {
#pragma GCC ivdep
  for (int j = 0; j < n; ++j) {
    const float x = b->x[j], y = b->y[j], z = b->z[j];
    const float px = (c.R[0] * x + c.R[1] * y) + c.R[2] * z + c.t[0];
    const float py = (c.R[3] * x + c.R[4] * y) + c.R[5] * z + c.t[1];
    const float pz = (c.R[6] * x + c.R[7] * y) + c.R[8] * z + c.t[2];
    // Eigen's order for a 3-vector's squaredNorm() and dot() (x + (y + z)), which the scalar cull
    // used: the same floats.
    const float d2 = px * px + (py * py + pz * pz);
    const float d = Sqrt(d2);
    const float radius = b->radius[j];
    const float mx = b->mx[j], my = b->my[j], mz = b->mz[j];
    const float nx = (c.R[0] * mx + c.R[1] * my) + c.R[2] * mz;
    const float ny = (c.R[3] * mx + c.R[4] * my) + c.R[5] * mz;
    const float nz = (c.R[6] * mx + c.R[7] * my) + c.R[8] * mz;
    const float n_dot_p = nx * px + (ny * py + nz * pz);
    // Bitwise & of the comparisons: no branches in the loop.
    const bool front = (d2 >= c.min_r2) & (d2 <= c.max_r2) & (radius > 0.0f) & (radius < d) &
                       (-n_dot_p > c.facing * d);
    // Pixel bounding box of the disc. Small discs: the linearised projection of the disc (an
    // ellipse with half-extent r * sqrt(|g|^2 - (g.n)^2) along an angle whose gradient is g),
    // widened by the relative second-order error 2a and a margin. Large or near-polar discs: the
    // cone of half-angle asin(radius / d) around p. Either bound is conservative; the ray test is
    // exact. a = tan(asin(radius / d)) = radius / sqrt(d^2 - radius^2) (tan >= asin).
    const float r2 = radius * radius;
    const float a = radius / Sqrt(d2 - r2) + kAngleMarginRad;
    const float inv_d2 = 1.0f / d2;
    const float rho2 = px * px + py * py;
    const float rho = Sqrt(rho2);
    const float pitch = internal::FastAtan2Branchless(pz, rho);
    // The linearised bound where the disc is small and away from the poles. Yaw gradient
    // g_y = (-y, x, 0) / rho^2 (|g_y|^2 = 1 / rho^2); pitch gradient g_p = (-x z, -y z, rho^2) /
    // (d^2 rho) (|g_p|^2 = 1 / d^2). With c = rho^2 g_y . n and q = d^2 rho g_p . n:
    // r sqrt(|g|^2 - (g.n)^2) = r sqrt(rho^2 - c^2) / rho^2 and r sqrt(d^2 rho^2 - q^2) / (d^2
    // rho).
    const bool linear = (a < kLinearBoundMaxAngle) & (rho > 0.5f * d);
    const float inv_rho = 1.0f / rho;
    const float cc = px * ny - py * nx;
    const float q = rho2 * nz - pz * (px * nx + py * ny);
    const float widen = radius * (1.0f + 2.0f * a);
    const float margin = a * a + kAngleMarginRad;
    const float e_yaw_lin = widen * inv_rho * inv_rho * Sqrt(MaxOf(0.0f, rho2 - cc * cc)) + margin;
    const float e_pitch_lin =
        widen * inv_rho * inv_d2 * Sqrt(MaxOf(0.0f, d2 * rho2 - q * q)) + margin;
    const float e_pitch = linear ? e_pitch_lin : a;
    const float v_lo = (c.fov_up - (pitch + e_pitch)) * c.rows_per_rad;
    const float v_hi = (c.fov_up - (pitch - e_pitch)) * c.rows_per_rad;
    const bool in_rows = !((v_hi < 0.0f) | (v_lo >= c.rows_f));
    // The cone bound's yaw half-width where the linearised one does not apply (-1: all columns).
    const float elev = MaxOf(Abs(pitch - a), Abs(pitch + a));
    const float s2 = radius / d / CosLowerBound(elev);
    const float e_yaw_cone = s2 / Sqrt(1.0f - s2 * s2) + kAngleMarginRad;
    const bool cone = (elev < 0.5f * internal::kPiF - 1e-3f) & (s2 < 1.0f);
    const float e_yaw = linear ? e_yaw_lin : (cone ? e_yaw_cone : -1.0f);
    const float yaw = internal::FastAtan2Branchless(py, px);
    b->px[j] = px;
    b->py[j] = py;
    b->pz[j] = pz;
    b->nx[j] = nx;
    b->ny[j] = ny;
    b->nz[j] = nz;
    b->n_dot_p[j] = n_dot_p;
    b->r2[j] = r2;
    b->v_lo[j] = v_lo;
    b->v_hi[j] = v_hi;
    b->u[j] = 0.5f * (1.0f - yaw * c.inv_pi) * c.cols_f;
    b->hu[j] = e_yaw * c.cols_per_rad;
    b->e_yaw[j] = e_yaw;
    b->visible[j] = static_cast<int32_t>(front & in_rows);
  }
}

}  // namespace

void CpuSurfelRenderer::Impl::Cull(const SurfelRenderInput& in, const Eigen::Matrix3f& R,
                                   const Eigen::Vector3f& t, size_t k0, size_t k1,
                                   BinnedRecords* bins) const {
  const RangeProjectionOptions& po = options.projection;
  const int rows = po.rows;
  const int cols = po.cols;
  CullConstants c;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) c.R[3 * i + j] = R(i, j);
    c.t[i] = t[i];
  }
  c.rows_f = static_cast<float>(rows);
  c.cols_f = static_cast<float>(cols);
  c.fov_up = static_cast<float>(po.fov_up_deg * M_PI / 180.0);
  const float fov = static_cast<float>((po.fov_up_deg - po.fov_down_deg) * M_PI / 180.0);
  c.rows_per_rad = c.rows_f / fov;
  c.cols_per_rad = c.cols_f / (2.0f * internal::kPiF);
  const float min_r = static_cast<float>(po.min_range_m);
  const float max_r = static_cast<float>(po.max_range_m);
  c.min_r2 = min_r * min_r;
  c.max_r2 = max_r * max_r;
  c.facing = static_cast<float>(options.min_facing_cos);
  c.inv_pi = 1.0f / internal::kPiF;

  CullBlockData b;
  // The surfels come by id, scattered over the map: fetch the one kPrefetch ahead while this one
  // is gathered (the load of each surfel was the cull's single largest stall).
  constexpr size_t kPrefetch = 16;
  for (size_t kb = k0; kb < k1; kb += kCullBlock) {
    const int n = static_cast<int>(std::min<size_t>(kCullBlock, k1 - kb));
    for (int j = 0; j < n; ++j) {
      const size_t k = kb + static_cast<size_t>(j);
      const size_t id = in.ids != nullptr ? in.ids[k] : k;
      if (in.ids != nullptr && k + kPrefetch < k1) {
        __builtin_prefetch(&in.surfels[in.ids[k + kPrefetch]]);
      }
      const Surfel& s = in.surfels[id];
      b.x[j] = s.position.x();
      b.y[j] = s.position.y();
      b.z[j] = s.position.z();
      b.mx[j] = s.normal.x();
      b.my[j] = s.normal.y();
      b.mz[j] = s.normal.z();
      b.radius[j] = s.radius;
    }
    BoundBlock(c, n, &b);
    for (int j = 0; j < n; ++j) {
      if (!b.visible[j]) continue;
      const int row0 = std::max(0, static_cast<int>(std::floor(b.v_lo[j])));
      const int row1 = std::min(rows - 1, static_cast<int>(std::floor(b.v_hi[j])));
      int col0 = 0;
      int col1 = cols - 1;
      if (b.e_yaw[j] >= 0.0f) {
        const int c0 = static_cast<int>(std::floor(b.u[j] - b.hu[j]));
        const int c1 = static_cast<int>(std::floor(b.u[j] + b.hu[j]));
        if (c1 - c0 + 1 < cols) {
          col0 = c0;
          col1 = c1;
        }
      }
      // The column span [col0, col1] (may cross the rear seam) as at most two wrapped ranges,
      // each split over the bins it touches.
      SplatRecord rec;
      rec.px = b.px[j];
      rec.py = b.py[j];
      rec.pz = b.pz[j];
      rec.nx = b.nx[j];
      rec.ny = b.ny[j];
      rec.nz = b.nz[j];
      rec.n_dot_p = b.n_dot_p[j];
      rec.r2 = b.r2[j];
      rec.k = static_cast<uint32_t>(kb + static_cast<size_t>(j));
      rec.row0 = row0;
      rec.row1 = row1;
      auto emit = [&](int c_lo, int c_hi) {
        if (c_lo > c_hi) return;
        for (int bin = c_lo / kBinCols; bin <= c_hi / kBinCols; ++bin) {
          rec.col0 = std::max(c_lo, bin * kBinCols);
          rec.col1 = std::min(c_hi, bin * kBinCols + kBinCols - 1);
          bins->Push(bin, rec);
        }
      };
      if (col0 < 0) {
        emit(col0 + cols, cols - 1);
        emit(0, std::min(col1, cols - 1));
      } else if (col1 >= cols) {
        emit(col0, cols - 1);
        emit(0, col1 - cols);
      } else {
        emit(col0, col1);
      }
    }
  }
}

void CpuSurfelRenderer::Impl::Raster(int b) {
  const int rows = options.projection.rows;
  const int cols = options.projection.cols;
  const float min_r = static_cast<float>(options.projection.min_range_m);
  const float max_r = static_cast<float>(options.projection.max_range_m);
  const float* row_cos = projection.row_cos().data();
  const float* row_sin = projection.row_sin().data();
  const float* col_cos = projection.col_cos().data();
  const float* col_sin = projection.col_sin().data();
  const int c_begin = b * kBinCols;
  const int c_end = std::min(cols, c_begin + kBinCols);
  DepthWinner* buf = depth.data();
  for (int row = 0; row < rows; ++row) {
    std::fill(buf + row * cols + c_begin, buf + row * cols + c_end,
              DepthWinner{std::numeric_limits<float>::infinity(), kNoWinner});
  }
  // Thread t culled draw positions below those of thread t + 1, so going through the threads in
  // order visits the records in draw order (ties go to the earlier surfel).
  const int num_threads = pool.num_threads();
  for (int ti = 0; ti < num_threads; ++ti) {
    records[static_cast<size_t>(ti)].ForEach(b, [&](const SplatRecord& r) {
      for (int row = r.row0; row <= r.row1; ++row) {
        // The pixel-centre ray, rebuilt from the small trig tables (bit-identical to the table
        // that EglSurfelRenderer uploads; the big table would cost a cache miss per pixel).
        const float cp = row_cos[row];
        const float sp = row_sin[row];
        const float nz_sp = r.nz * sp;
        DepthWinner* line = buf + row * cols;
        for (int c = r.col0; c <= r.col1; ++c) {
          const float rx = cp * col_cos[c];
          const float ry = cp * col_sin[c];
          const float denom = r.nx * rx + r.ny * ry + nz_sp;
          if (!(denom < 0.0f)) continue;
          // Division-free early tests (denom < 0): t = n.p / denom < depth <=> n.p > depth *
          // denom, and |t d - p|^2 <= r^2 <=> |(n.p) d - denom p|^2 <= r^2 denom^2. The depth
          // test is loosened by kDepthSlack so that rounding never rejects a t that the exact
          // test below accepts (the result must not depend on the order the discs come in).
          DepthWinner& dw = line[c];
          if (!(r.n_dot_p > dw.depth * (denom * kDepthSlack))) continue;
          const float hx = r.n_dot_p * rx - denom * r.px;
          const float hy = r.n_dot_p * ry - denom * r.py;
          const float hz = r.n_dot_p * sp - denom * r.pz;
          if (hx * hx + hy * hy + hz * hz > r.r2 * (denom * denom)) continue;
          const float tt = r.n_dot_p / denom;
          if (!(tt < dw.depth) || tt < min_r || tt > max_r) continue;
          dw.depth = tt;
          dw.winner = r.k;
        }
      }
    });
  }
}

CpuSurfelRenderer::CpuSurfelRenderer()
    : impl_(std::make_unique<Impl>(SurfelRendererOptions(), 2)) {}
CpuSurfelRenderer::CpuSurfelRenderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
CpuSurfelRenderer::~CpuSurfelRenderer() = default;
CpuSurfelRenderer::CpuSurfelRenderer(CpuSurfelRenderer&&) noexcept = default;
CpuSurfelRenderer& CpuSurfelRenderer::operator=(CpuSurfelRenderer&&) noexcept = default;

StatusOr<std::unique_ptr<CpuSurfelRenderer>> CpuSurfelRenderer::Create(
    const SurfelRendererOptions& options, int num_threads) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (num_threads < 1 || num_threads > 64) {
    return internal::OptionError("CpuSurfelRenderer::Create", "num_threads", num_threads,
                                 "must be in [1, 64]");
  }
  return std::unique_ptr<CpuSurfelRenderer>(
      new CpuSurfelRenderer(std::make_unique<Impl>(options, num_threads)));
}

const RangeProjection& CpuSurfelRenderer::projection() const { return impl_->projection; }
const SurfelRendererOptions& CpuSurfelRenderer::options() const { return impl_->options; }

Status CpuSurfelRenderer::Render(const SurfelRenderInput& input,
                                 const Eigen::Isometry3d& T_world_sensor, VertexNormalMap* out) {
  if (out == nullptr) return InvalidArgumentError("CpuSurfelRenderer::Render: out is null");
  SLAM_MMS_RETURN_IF_ERROR(ValidateRenderInput(input));
  if (!T_world_sensor.matrix().allFinite()) {
    return InvalidArgumentError("CpuSurfelRenderer::Render: T_world_sensor is not finite");
  }
  Impl& m = *impl_;
  const int rows = m.projection.rows();
  const int cols = m.projection.cols();
  const size_t num_pixels = static_cast<size_t>(rows) * static_cast<size_t>(cols);
  if (out->rows != rows || out->cols != cols || out->range.size() != num_pixels) {
    out->Reset(rows, cols);
  }
  const Eigen::Isometry3d T_sensor_world = T_world_sensor.inverse();
  const Eigen::Matrix3f R = T_sensor_world.linear().cast<float>();
  const Eigen::Vector3f t = T_sensor_world.translation().cast<float>();
  const size_t n = input.count();
  const int num_threads = m.pool.num_threads();
  const size_t chunk =
      (n + static_cast<size_t>(num_threads) - 1) / static_cast<size_t>(num_threads);

  // Pass 1: each thread culls its contiguous chunk of draw positions into per-bin records.
  m.pool.Run([&](int ti) {
    BinnedRecords* bins = &m.records[static_cast<size_t>(ti)];
    bins->Clear(m.num_bins);
    const size_t k0 = std::min(n, static_cast<size_t>(ti) * chunk);
    const size_t k1 = std::min(n, k0 + chunk);
    m.Cull(input, R, t, k0, k1, bins);
  });

  // Pass 2: the threads take bins in turn; each bin is rastered (nearest wins, ties to the earlier
  // draw position) and its output pixels written while they are still in cache.
  const Eigen::Vector3f* rays = m.projection.ray_directions().data();
  m.next_bin.store(0, std::memory_order_relaxed);
  m.pool.Run([&](int) {
    for (int b = m.next_bin.fetch_add(1, std::memory_order_relaxed); b < m.num_bins;
         b = m.next_bin.fetch_add(1, std::memory_order_relaxed)) {
      m.Raster(b);
      const int c_begin = b * kBinCols;
      const int c_end = std::min(cols, c_begin + kBinCols);
      for (int row = 0; row < rows; ++row) {
        for (int c = c_begin; c < c_end; ++c) {
          const size_t i =
              static_cast<size_t>(row) * static_cast<size_t>(cols) + static_cast<size_t>(c);
          const DepthWinner dw = m.depth[i];
          if (dw.winner == kNoWinner) {
            out->vertex[i].setZero();
            out->normal[i].setZero();
            out->range[i] = 0.0f;
            out->index[i] = -1;
            continue;
          }
          const size_t id = input.ids != nullptr ? input.ids[dw.winner] : dw.winner;
          out->vertex[i] = dw.depth * rays[i];
          out->normal[i] = R * input.surfels[id].normal;
          out->range[i] = dw.depth;
          out->index[i] = static_cast<int32_t>(id);
        }
      }
    }
  });
  return OkStatus();
}

}  // namespace slam_mms
