#include "slam_mms/surfel/cpu_surfel_renderer.hpp"

#include <algorithm>
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
// Discs subtending less than this [rad] are bounded by their linearised projection.
constexpr float kLinearBoundMaxAngle = 0.1f;

// Lower bound of cos(e) for e in [0, pi/2] (alternating Taylor series cut after a negative term).
inline float CosLowerBound(float e) {
  const float e2 = e * e;
  return 1.0f - e2 * (0.5f - e2 * (1.0f / 24.0f - e2 * (1.0f / 720.0f)));
}

}  // namespace

struct CpuSurfelRenderer::Impl {
  explicit Impl(const SurfelRendererOptions& o)
      : options(o),
        projection(*RangeProjection::Create(o.projection)),
        pool(o.num_threads),
        buffers(static_cast<size_t>(o.num_threads)) {
    const size_t n =
        static_cast<size_t>(o.projection.rows) * static_cast<size_t>(o.projection.cols);
    for (auto& b : buffers) b.resize(n);
  }

  // Splats draw positions [k0, k1) into one thread's buffers.
  void Splat(const SurfelRenderInput& in, const Eigen::Matrix3f& R, const Eigen::Vector3f& t,
             size_t k0, size_t k1, DepthWinner* buf) const;

  SurfelRendererOptions options;
  RangeProjection projection;
  internal::WorkerPool pool;
  // Per thread, rows * cols: nearest depth and the draw position of its surfel.
  std::vector<std::vector<DepthWinner>> buffers;
};

void CpuSurfelRenderer::Impl::Splat(const SurfelRenderInput& in, const Eigen::Matrix3f& R,
                                    const Eigen::Vector3f& t, size_t k0, size_t k1,
                                    DepthWinner* buf) const {
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
  const float* row_cos = projection.row_cos().data();
  const float* row_sin = projection.row_sin().data();
  const float* col_cos = projection.col_cos().data();
  const float* col_sin = projection.col_sin().data();

  for (size_t k = k0; k < k1; ++k) {
    const size_t id = in.ids != nullptr ? in.ids[k] : k;
    const Surfel& s = in.surfels[id];
    const Eigen::Vector3f p = R * s.position + t;
    const float d2 = p.squaredNorm();
    if (!(d2 >= min_r2 && d2 <= max_r2)) continue;
    const float d = std::sqrt(d2);
    const float radius = s.radius;
    if (!(radius > 0.0f) || !(radius < d)) continue;
    const Eigen::Vector3f n = R * s.normal;
    const float n_dot_p = n.dot(p);
    if (!(-n_dot_p > facing * d)) continue;

    // Pixel bounding box of the disc. Small discs: the linearised projection of the disc (an
    // ellipse with half-extent r * sqrt(|g|^2 - (g.n)^2) along an angle whose gradient is g),
    // widened by the relative second-order error 2a and a margin. Large or near-polar discs: the
    // cone of half-angle asin(radius / d) around p. Either bound is conservative; the ray test is
    // exact.
    const float sin_a = radius / d;
    const float a = sin_a / std::sqrt(1.0f - sin_a * sin_a) + kAngleMarginRad;  // tan >= asin
    const float rho2 = p.x() * p.x() + p.y() * p.y();
    const float rho = std::sqrt(rho2);
    const float pitch = internal::FastAtan2(p.z(), rho);
    float e_pitch = a;
    float e_yaw = -1.0f;  // < 0: use the cone bound
    if (a < kLinearBoundMaxAngle && rho > 0.5f * d) {
      const float inv_rho2 = 1.0f / rho2;
      const Eigen::Vector3f g_yaw(-p.y() * inv_rho2, p.x() * inv_rho2, 0.0f);
      const float k = 1.0f / (d2 * rho);
      const Eigen::Vector3f g_pitch(-p.x() * p.z() * k, -p.y() * p.z() * k, rho2 * k);
      const float widen = radius * (1.0f + 2.0f * a);
      const float margin = a * a + kAngleMarginRad;
      const float gn_y = g_yaw.dot(n);
      const float gn_p = g_pitch.dot(n);
      e_yaw = widen * std::sqrt(std::max(0.0f, g_yaw.squaredNorm() - gn_y * gn_y)) + margin;
      e_pitch = widen * std::sqrt(std::max(0.0f, g_pitch.squaredNorm() - gn_p * gn_p)) + margin;
    }
    const float v_lo = (fov_up - (pitch + e_pitch)) * rows_per_rad;
    const float v_hi = (fov_up - (pitch - e_pitch)) * rows_per_rad;
    if (v_hi < 0.0f || v_lo >= rows_f) continue;
    const int row0 = std::max(0, static_cast<int>(std::floor(v_lo)));
    const int row1 = std::min(rows - 1, static_cast<int>(std::floor(v_hi)));
    if (e_yaw < 0.0f) {
      const float elev = std::max(std::fabs(pitch - a), std::fabs(pitch + a));
      if (elev < 0.5f * internal::kPiF - 1e-3f) {
        const float s2 = sin_a / CosLowerBound(elev);
        if (s2 < 1.0f) e_yaw = s2 / std::sqrt(1.0f - s2 * s2) + kAngleMarginRad;
      }
    }
    int col0 = 0;
    int col1 = cols - 1;
    if (e_yaw >= 0.0f) {
      const float yaw = internal::FastAtan2(p.y(), p.x());
      const float u = 0.5f * (1.0f - yaw / internal::kPiF) * cols_f;
      const float hu = e_yaw * cols_per_rad;
      const int c0 = static_cast<int>(std::floor(u - hu));
      const int c1 = static_cast<int>(std::floor(u + hu));
      if (c1 - c0 + 1 < cols) {
        col0 = c0;
        col1 = c1;
      }
    }
    const float r2 = radius * radius;
    const uint32_t kk = static_cast<uint32_t>(k);
    for (int row = row0; row <= row1; ++row) {
      // The pixel-centre ray, rebuilt from the small trig tables (bit-identical to the table that
      // EglSurfelRenderer uploads; the big table would cost a cache miss per pixel).
      const float cp = row_cos[row];
      const float sp = row_sin[row];
      const float nz_sp = n.z() * sp;
      DepthWinner* line = buf + row * cols;
      for (int c = col0; c <= col1; ++c) {
        const int cw = c < 0 ? c + cols : (c >= cols ? c - cols : c);
        const float rx = cp * col_cos[cw];
        const float ry = cp * col_sin[cw];
        const float denom = n.x() * rx + n.y() * ry + nz_sp;
        if (!(denom < 0.0f)) continue;
        // Division-free early tests (denom < 0): t = n.p / denom < depth <=> n.p > depth * denom,
        // and |t d - p|^2 <= r^2 <=> |(n.p) d - denom p|^2 <= r^2 denom^2.
        DepthWinner& dw = line[cw];
        if (!(n_dot_p > dw.depth * denom)) continue;
        const float hx = n_dot_p * rx - denom * p.x();
        const float hy = n_dot_p * ry - denom * p.y();
        const float hz = n_dot_p * sp - denom * p.z();
        if (hx * hx + hy * hy + hz * hz > r2 * (denom * denom)) continue;
        const float tt = n_dot_p / denom;
        if (!(tt < dw.depth) || tt < min_r || tt > max_r) continue;
        dw.depth = tt;
        dw.winner = kk;
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

  // Pass 1: each thread splats its chunk of surfels into its own buffers.
  m.pool.Run([&](int ti) {
    DepthWinner* buf = m.buffers[static_cast<size_t>(ti)].data();
    std::fill(buf, buf + num_pixels,
              DepthWinner{std::numeric_limits<float>::infinity(), kNoWinner});
    const size_t k0 = std::min(n, static_cast<size_t>(ti) * chunk);
    const size_t k1 = std::min(n, k0 + chunk);
    m.Splat(input, R, t, k0, k1, buf);
  });

  // Pass 2: merge (nearest wins, ties to the earlier draw position) and write each pixel once.
  const Eigen::Vector3f* rays = m.projection.ray_directions().data();
  const size_t pix_chunk =
      (num_pixels + static_cast<size_t>(num_threads) - 1) / static_cast<size_t>(num_threads);
  m.pool.Run([&](int ti) {
    const size_t i0 = std::min(num_pixels, static_cast<size_t>(ti) * pix_chunk);
    const size_t i1 = std::min(num_pixels, i0 + pix_chunk);
    for (size_t i = i0; i < i1; ++i) {
      float best = m.buffers[0][i].depth;
      uint32_t win = m.buffers[0][i].winner;
      for (size_t j = 1; j < m.buffers.size(); ++j) {
        const float dj = m.buffers[j][i].depth;
        const uint32_t wj = m.buffers[j][i].winner;
        if (dj < best || (dj == best && wj < win)) {
          best = dj;
          win = wj;
        }
      }
      if (win == kNoWinner) {
        out->vertex[i].setZero();
        out->normal[i].setZero();
        out->range[i] = 0.0f;
        out->index[i] = -1;
        continue;
      }
      const size_t id = input.ids != nullptr ? input.ids[win] : win;
      out->vertex[i] = best * rays[i];
      out->normal[i] = R * input.surfels[id].normal;
      out->range[i] = best;
      out->index[i] = static_cast<int32_t>(id);
    }
  });
  return OkStatus();
}

}  // namespace slam_mms
