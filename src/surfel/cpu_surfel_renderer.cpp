#include "slam_mms/surfel/cpu_surfel_renderer.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <utility>

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

}  // namespace

struct CpuSurfelRenderer::Impl {
  explicit Impl(const SurfelRendererOptions& o)
      : options(o),
        projection(*RangeProjection::Create(o.projection)),
        pool(o.num_threads),
        num_bins((o.projection.cols + kBinCols - 1) / kBinCols),
        records(static_cast<size_t>(o.num_threads) * static_cast<size_t>(num_bins)) {
    depth.resize(static_cast<size_t>(o.projection.rows) * static_cast<size_t>(o.projection.cols));
  }

  // Culls draw positions [k0, k1) and appends their splat records to bins[0 .. num_bins).
  void Cull(const SurfelRenderInput& in, const Eigen::Matrix3f& R, const Eigen::Vector3f& t,
            size_t k0, size_t k1, std::vector<SplatRecord>* bins) const;
  // Rasters bin b's records (all threads', in draw order) into `depth`.
  void Raster(int b);

  SurfelRendererOptions options;
  RangeProjection projection;
  internal::WorkerPool pool;
  int num_bins;
  // records[thread * num_bins + bin], reused across calls.
  std::vector<std::vector<SplatRecord>> records;
  // rows * cols: nearest depth and the draw position of its surfel.
  std::vector<DepthWinner> depth;
  std::atomic<int> next_bin{0};
};

void CpuSurfelRenderer::Impl::Cull(const SurfelRenderInput& in, const Eigen::Matrix3f& R,
                                   const Eigen::Vector3f& t, size_t k0, size_t k1,
                                   std::vector<SplatRecord>* bins) const {
  const RangeProjectionOptions& po = options.projection;
  const int rows = po.rows;
  const int cols = po.cols;
  const float rows_f = static_cast<float>(rows);
  const float cols_f = static_cast<float>(cols);
  const float fov_up = static_cast<float>(po.fov_up_deg * M_PI / 180.0);
  const float fov = static_cast<float>((po.fov_up_deg - po.fov_down_deg) * M_PI / 180.0);
  const float rows_per_rad = rows_f / fov;
  const float cols_per_rad = cols_f / (2.0f * internal::kPiF);
  const float min_r = static_cast<float>(po.min_range_m);
  const float max_r = static_cast<float>(po.max_range_m);
  const float min_r2 = min_r * min_r;
  const float max_r2 = max_r * max_r;
  const float facing = static_cast<float>(options.min_facing_cos);
  const float kInvPi = 1.0f / internal::kPiF;

  // The surfels come by id, scattered over the map: fetch the one kPrefetch ahead while this one
  // is bounded (the load of each surfel was the cull's single largest stall).
  constexpr size_t kPrefetch = 16;
  for (size_t k = k0; k < k1; ++k) {
    const size_t id = in.ids != nullptr ? in.ids[k] : k;
    if (in.ids != nullptr && k + kPrefetch < k1)
      __builtin_prefetch(&in.surfels[in.ids[k + kPrefetch]]);
    const Surfel& s = in.surfels[id];
    // p = R x + t and n = R m written out (Eigen's product is not always inlined here; same
    // operation order, so the same floats).
    const Eigen::Vector3f& x = s.position;
    const Eigen::Vector3f p((R(0, 0) * x.x() + R(0, 1) * x.y()) + R(0, 2) * x.z() + t.x(),
                            (R(1, 0) * x.x() + R(1, 1) * x.y()) + R(1, 2) * x.z() + t.y(),
                            (R(2, 0) * x.x() + R(2, 1) * x.y()) + R(2, 2) * x.z() + t.z());
    const float d2 = p.squaredNorm();
    if (!(d2 >= min_r2 && d2 <= max_r2)) continue;
    const float d = std::sqrt(d2);
    const float radius = s.radius;
    if (!(radius > 0.0f) || !(radius < d)) continue;
    const Eigen::Vector3f& m = s.normal;
    const Eigen::Vector3f n((R(0, 0) * m.x() + R(0, 1) * m.y()) + R(0, 2) * m.z(),
                            (R(1, 0) * m.x() + R(1, 1) * m.y()) + R(1, 2) * m.z(),
                            (R(2, 0) * m.x() + R(2, 1) * m.y()) + R(2, 2) * m.z());
    const float n_dot_p = n.dot(p);
    if (!(-n_dot_p > facing * d)) continue;

    // Pixel bounding box of the disc. Small discs: the linearised projection of the disc (an
    // ellipse with half-extent r * sqrt(|g|^2 - (g.n)^2) along an angle whose gradient is g),
    // widened by the relative second-order error 2a and a margin. Large or near-polar discs: the
    // cone of half-angle asin(radius / d) around p. Either bound is conservative; the ray test is
    // exact.
    // The long-latency divisions and roots below are kept independent of each other so that they
    // overlap: a = tan(asin(radius / d)) = radius / sqrt(d^2 - radius^2) (tan >= asin).
    const float r2 = radius * radius;
    const float a = radius / std::sqrt(d2 - r2) + kAngleMarginRad;
    const float inv_d2 = 1.0f / d2;
    const float rho2 = p.x() * p.x() + p.y() * p.y();
    const float rho = std::sqrt(rho2);
    const float pitch = internal::FastAtan2(p.z(), rho);
    float e_pitch = a;
    float e_yaw = -1.0f;  // < 0: use the cone bound
    if (a < kLinearBoundMaxAngle && rho > 0.5f * d) {
      // Yaw gradient g_y = (-y, x, 0) / rho^2 (|g_y|^2 = 1 / rho^2); pitch gradient
      // g_p = (-x z, -y z, rho^2) / (d^2 rho) (|g_p|^2 = 1 / d^2). With c = rho^2 g_y . n and
      // q = d^2 rho g_p . n: r sqrt(|g|^2 - (g.n)^2) = r sqrt(rho^2 - c^2) / rho^2 and
      // r sqrt(d^2 rho^2 - q^2) / (d^2 rho).
      const float inv_rho = 1.0f / rho;
      const float c = p.x() * n.y() - p.y() * n.x();
      const float q = rho2 * n.z() - p.z() * (p.x() * n.x() + p.y() * n.y());
      const float widen = radius * (1.0f + 2.0f * a);
      const float margin = a * a + kAngleMarginRad;
      e_yaw = widen * inv_rho * inv_rho * std::sqrt(std::max(0.0f, rho2 - c * c)) + margin;
      e_pitch = widen * inv_rho * inv_d2 * std::sqrt(std::max(0.0f, d2 * rho2 - q * q)) + margin;
    }
    const float v_lo = (fov_up - (pitch + e_pitch)) * rows_per_rad;
    const float v_hi = (fov_up - (pitch - e_pitch)) * rows_per_rad;
    if (v_hi < 0.0f || v_lo >= rows_f) continue;
    const int row0 = std::max(0, static_cast<int>(std::floor(v_lo)));
    const int row1 = std::min(rows - 1, static_cast<int>(std::floor(v_hi)));
    if (e_yaw < 0.0f) {
      const float elev = std::max(std::fabs(pitch - a), std::fabs(pitch + a));
      if (elev < 0.5f * internal::kPiF - 1e-3f) {
        const float s2 = radius / d / CosLowerBound(elev);
        if (s2 < 1.0f) e_yaw = s2 / std::sqrt(1.0f - s2 * s2) + kAngleMarginRad;
      }
    }
    int col0 = 0;
    int col1 = cols - 1;
    if (e_yaw >= 0.0f) {
      const float yaw = internal::FastAtan2(p.y(), p.x());
      const float u = 0.5f * (1.0f - yaw * kInvPi) * cols_f;
      const float hu = e_yaw * cols_per_rad;
      const int c0 = static_cast<int>(std::floor(u - hu));
      const int c1 = static_cast<int>(std::floor(u + hu));
      if (c1 - c0 + 1 < cols) {
        col0 = c0;
        col1 = c1;
      }
    }
    // The column span [col0, col1] (may cross the rear seam) as at most two wrapped ranges, each
    // split over the bins it touches.
    SplatRecord rec;
    rec.px = p.x();
    rec.py = p.y();
    rec.pz = p.z();
    rec.nx = n.x();
    rec.ny = n.y();
    rec.nz = n.z();
    rec.n_dot_p = n_dot_p;
    rec.r2 = r2;
    rec.k = static_cast<uint32_t>(k);
    rec.row0 = row0;
    rec.row1 = row1;
    auto emit = [&](int c_lo, int c_hi) {
      if (c_lo > c_hi) return;
      for (int b = c_lo / kBinCols; b <= c_hi / kBinCols; ++b) {
        rec.col0 = std::max(c_lo, b * kBinCols);
        rec.col1 = std::min(c_hi, b * kBinCols + kBinCols - 1);
        bins[b].push_back(rec);
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
    const std::vector<SplatRecord>& list =
        records[static_cast<size_t>(ti) * static_cast<size_t>(num_bins) + static_cast<size_t>(b)];
    for (const SplatRecord& r : list) {
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
    }
  }
}

CpuSurfelRenderer::CpuSurfelRenderer() : impl_(std::make_unique<Impl>(SurfelRendererOptions())) {}
CpuSurfelRenderer::CpuSurfelRenderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
CpuSurfelRenderer::~CpuSurfelRenderer() = default;
CpuSurfelRenderer::CpuSurfelRenderer(CpuSurfelRenderer&&) noexcept = default;
CpuSurfelRenderer& CpuSurfelRenderer::operator=(CpuSurfelRenderer&&) noexcept = default;

StatusOr<std::unique_ptr<CpuSurfelRenderer>> CpuSurfelRenderer::Create(
    const SurfelRendererOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  return std::unique_ptr<CpuSurfelRenderer>(new CpuSurfelRenderer(std::make_unique<Impl>(options)));
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
  const size_t nb = static_cast<size_t>(m.num_bins);

  // Pass 1: each thread culls its contiguous chunk of draw positions into per-bin records.
  m.pool.Run([&](int ti) {
    std::vector<SplatRecord>* bins = &m.records[static_cast<size_t>(ti) * nb];
    for (size_t b = 0; b < nb; ++b) bins[b].clear();
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
