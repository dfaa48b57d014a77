#include "registration/projective_icp.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "core/float_transform.hpp"
#include "core/option_error.hpp"
#include "core/worker_pool.hpp"
#include "registration/gauss_newton.hpp"
#include "registration/point_to_plane.hpp"

namespace slam_mms {
namespace {

using internal::WorkerPool;
using registration_internal::GaussNewtonSettings;
using registration_internal::NormalEquations;
using registration_internal::PointToPlaneResidual;

constexpr float kPiF = 3.14159265358979f;

// atan2 with max error ~1e-5 rad (0.3% of a 2048-column pixel), ~4x faster than std::atan2.
inline float FastAtan2(float y, float x) {
  const float ax = __builtin_fabsf(x), ay = __builtin_fabsf(y);
  const float mx = ax > ay ? ax : ay;
  const float mn = ax > ay ? ay : ax;
  const float a = mn / (mx + 1e-30f);
  const float s = a * a;
  float r = ((-0.0464964749f * s + 0.15931422f) * s - 0.327622764f) * s * a + a;
  r = ay > ax ? 0.5f * kPiF - r : r;
  r = x < 0.0f ? kPiF - r : r;
  return y < 0.0f ? -r : r;
}

// A packed scan pixel with vertex and normal (scan frame).
struct ScanPoint {
  Eigen::Vector3f v, n;
};

struct ProjectionConstants {
  float rows, cols;
  int rows_i, cols_i;
  float fov_up, inv_fov, u_scale;
};

// The projection of a block of scan points into the model image, in one branch-free loop that
// the compiler vectorises (this file is built with -fno-math-errno -fno-trapping-math; no value
// changes): the same floats as the per-point code it replaced (Eigen's R x + t order,
// (a + (b + c)) + t), and the pixel or -1 where the point falls outside the image rows.
struct ProjectedBlock {
  static constexpr int kSize = 64;
  alignas(64) float x[kSize], y[kSize], z[kSize];
  alignas(64) float qx[kSize], qy[kSize], qz[kSize];
  alignas(64) int32_t pixel[kSize];

  void Project(const Eigen::Matrix3f& R, const Eigen::Vector3f& t, const ScanPoint* points, int n,
               const ProjectionConstants& c) {
    for (int b = 0; b < n; ++b) {
      x[b] = points[b].v.x();
      y[b] = points[b].v.y();
      z[b] = points[b].v.z();
    }
    const internal::FloatTransform T(R, t);
#pragma GCC ivdep
    for (int b = 0; b < n; ++b) {
      float px, py, pz;
      T.Apply(x[b], y[b], z[b], &px, &py, &pz);
      // Spherical projection (RangeProjection's mapping) of q into the model image.
      const float xy = __builtin_sqrtf(px * px + py * py);
      float u = 0.5f * c.cols - FastAtan2(py, px) * c.u_scale;
      const float v = (c.fov_up - FastAtan2(pz, xy)) * c.inv_fov * c.rows;
      const bool in_rows = (v >= 0.0f) & (v < c.rows);
      u = u >= c.cols ? u - c.cols : u;
      u = u < 0.0f ? u + c.cols : u;
      int col = static_cast<int>(u);
      col = col >= c.cols_i ? c.cols_i - 1 : col;
      int row = static_cast<int>(v);
      row = row >= c.rows_i ? c.rows_i - 1 : row;
      qx[b] = px;
      qy[b] = py;
      qz[b] = pz;
      pixel[b] = in_rows ? row * c.cols_i + col : -1;
    }
  }
};

// Upper triangle of H (21), g (6) and statistics. Per point the products are summed in float over
// blocks of kBlock points (vectorisable), then flushed into double accumulators, so precision stays
// that of double sums of float terms while the hot loop stays in float.
struct Accumulator {
  static constexpr int kBlock = 128;
  double H[21];
  double g[6];
  double weighted_r2, r2;
  double m2[3];
  size_t inliers, candidates;
  float hf[21 + 6 + 2 + 3];  // block sums: H, g, w r^2, r^2, p.^2
  int in_block;

  void Zero() { *this = Accumulator{}; }
  inline void Add(const Eigen::Matrix<float, 6, 1>& J, float r, float w, const Eigen::Vector3f& p) {
    float wj[6];
    for (int i = 0; i < 6; ++i) wj[i] = w * J[i];
    int k = 0;
    for (int i = 0; i < 6; ++i) {
      for (int j = i; j < 6; ++j) hf[k++] += wj[i] * J[j];
    }
    for (int i = 0; i < 6; ++i) hf[21 + i] += wj[i] * r;
    hf[27] += w * r * r;
    hf[28] += r * r;
    hf[29] += p.x() * p.x();
    hf[30] += p.y() * p.y();
    hf[31] += p.z() * p.z();
    ++inliers;
    if (++in_block == kBlock) Flush();
  }
  void Flush() {
    for (int i = 0; i < 21; ++i) H[i] += static_cast<double>(hf[i]);
    for (int i = 0; i < 6; ++i) g[i] += static_cast<double>(hf[21 + i]);
    weighted_r2 += static_cast<double>(hf[27]);
    r2 += static_cast<double>(hf[28]);
    for (int i = 0; i < 3; ++i) m2[i] += static_cast<double>(hf[29 + i]);
    for (float& x : hf) x = 0.0f;
    in_block = 0;
  }
  void AddTo(NormalEquations* eq) const {
    int k = 0;
    for (int i = 0; i < 6; ++i) {
      for (int j = i; j < 6; ++j) eq->H(i, j) += H[k++];
    }
    for (int i = 0; i < 6; ++i) eq->g[i] += g[i];
    eq->weighted_r2 += weighted_r2;
    eq->r2 += r2;
    eq->moment2 += Eigen::Vector3d(m2[0], m2[1], m2[2]);
    eq->inliers += inliers;
    eq->candidates += candidates;
  }
};

Status FieldError(const std::string& field, double value, const std::string& rule) {
  return internal::OptionError("ProjectiveIcp::Options", field, value, rule);
}

Status CheckMap(const VertexNormalMap& m, const char* what) {
  const size_t n = static_cast<size_t>(m.rows) * static_cast<size_t>(m.cols);
  if (m.rows <= 0 || m.cols <= 0 || m.vertex.size() != n || m.normal.size() != n ||
      m.range.size() != n) {
    return InvalidArgumentError(std::string("ProjectiveIcp::Align: ") + what + " map is " +
                                std::to_string(m.rows) + " x " + std::to_string(m.cols) +
                                " with inconsistent or empty vertex/normal/range arrays");
  }
  return OkStatus();
}

}  // namespace

Status ProjectiveIcpOptions::Validate() const {
  if (!(max_distance > 0.0)) return FieldError("max_distance", max_distance, "must be > 0");
  if (!(max_angle_deg > 0.0 && max_angle_deg <= 180.0))
    return FieldError("max_angle_deg", max_angle_deg, "must be in (0, 180]");
  if (!std::isfinite(huber_delta)) return FieldError("huber_delta", huber_delta, "must be finite");
  if (max_iterations <= 0) return FieldError("max_iterations", max_iterations, "must be > 0");
  if (min_correspondences < 6)
    return FieldError("min_correspondences", min_correspondences, "must be >= 6");
  if (!(rotation_eps > 0.0)) return FieldError("rotation_eps", rotation_eps, "must be > 0");
  if (!(translation_eps > 0.0))
    return FieldError("translation_eps", translation_eps, "must be > 0");
  if (!(degeneracy_threshold > 0.0 && degeneracy_threshold < 1.0))
    return FieldError("degeneracy_threshold", degeneracy_threshold, "must be in (0, 1)");
  if (pixel_stride < 1) return FieldError("pixel_stride", pixel_stride, "must be >= 1");
  return OkStatus();
}

Status ProjectiveIcp::Options::Validate() const {
  SLAM_MMS_RETURN_IF_ERROR(ProjectiveIcpOptions::Validate());
  if (num_threads < 1 || num_threads > 256)
    return FieldError("num_threads", num_threads, "must be in [1, 256]");
  return OkStatus();
}

struct ProjectiveIcp::Impl {
  Impl(const RangeProjection& p, const Options& o)
      : options(o), projection(p.options()), pool(o.num_threads) {
    per_thread.resize(static_cast<size_t>(pool.size()));
    blocks.resize(static_cast<size_t>(pool.size()));
  }
  Options options;
  RangeProjectionOptions projection;
  WorkerPool pool;
  std::vector<Accumulator> per_thread;
  std::vector<ScanPoint> valid;        // packed scan pixels with vertex and normal (scratch)
  std::vector<ProjectedBlock> blocks;  // per thread
};

ProjectiveIcp::ProjectiveIcp() : impl_(std::make_unique<Impl>(RangeProjection(), Options())) {}
ProjectiveIcp::ProjectiveIcp(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ProjectiveIcp::~ProjectiveIcp() = default;
ProjectiveIcp::ProjectiveIcp(ProjectiveIcp&&) noexcept = default;
ProjectiveIcp& ProjectiveIcp::operator=(ProjectiveIcp&&) noexcept = default;

StatusOr<ProjectiveIcp> ProjectiveIcp::Create(const RangeProjection& projection,
                                              const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  SLAM_MMS_RETURN_IF_ERROR(projection.options().Validate());
  return ProjectiveIcp(std::make_unique<Impl>(projection, options));
}

const ProjectiveIcp::Options& ProjectiveIcp::options() const { return impl_->options; }

StatusOr<RegistrationResult> ProjectiveIcp::Align(const VertexNormalMap& scan,
                                                  const VertexNormalMap& model,
                                                  const Eigen::Isometry3d& T_model_scan_init) {
  Impl& m = *impl_;
  SLAM_MMS_RETURN_IF_ERROR(CheckMap(scan, "scan"));
  SLAM_MMS_RETURN_IF_ERROR(CheckMap(model, "model"));
  if (model.rows != m.projection.rows || model.cols != m.projection.cols) {
    return InvalidArgumentError("ProjectiveIcp::Align: model map is " + std::to_string(model.rows) +
                                " x " + std::to_string(model.cols) + " but the projection is " +
                                std::to_string(m.projection.rows) + " x " +
                                std::to_string(m.projection.cols));
  }
  if (!T_model_scan_init.matrix().allFinite())
    return InvalidArgumentError("ProjectiveIcp::Align: T_model_scan_init is not finite");

  m.valid.clear();
  const int stride = m.options.pixel_stride;
  int count = 0;
  for (int i = 0; i < scan.size(); ++i) {
    if (!scan.HasVertex(i) || !scan.HasNormal(i)) continue;
    if (count++ % stride == 0) {
      m.valid.push_back({scan.vertex[static_cast<size_t>(i)], scan.normal[static_cast<size_t>(i)]});
    }
  }

  ProjectionConstants proj;
  proj.rows = static_cast<float>(model.rows);
  proj.cols = static_cast<float>(model.cols);
  proj.cols_i = model.cols;
  proj.rows_i = model.rows;
  proj.fov_up = static_cast<float>(m.projection.fov_up_deg * M_PI / 180.0);
  proj.inv_fov = static_cast<float>(
      1.0 / ((m.projection.fov_up_deg - m.projection.fov_down_deg) * M_PI / 180.0));
  proj.u_scale = 0.5f * proj.cols / kPiF;  // u = cols/2 - yaw * cols / (2 pi)
  const float max_d2 = static_cast<float>(m.options.max_distance * m.options.max_distance);
  const float min_cos = static_cast<float>(std::cos(m.options.max_angle_deg * M_PI / 180.0));
  const float huber = static_cast<float>(m.options.huber_delta);

  GaussNewtonSettings s;
  s.max_iterations = m.options.max_iterations;
  s.min_correspondences = static_cast<size_t>(m.options.min_correspondences);
  s.rotation_eps_rad = m.options.rotation_eps;
  s.translation_eps_m = m.options.translation_eps;
  s.degeneracy_threshold = m.options.degeneracy_threshold;
  s.freeze_degenerate_directions = m.options.freeze_degenerate_directions;

  auto build = [&](const Eigen::Isometry3d& T, NormalEquations* eq) {
    const Eigen::Matrix3f R = T.linear().cast<float>();
    const Eigen::Vector3f t = T.translation().cast<float>();
    auto job = [&](int th) {
      Accumulator& acc = m.per_thread[static_cast<size_t>(th)];
      acc.Zero();
      size_t begin, end;
      m.pool.Range(th, m.valid.size(), &begin, &end);
      acc.candidates = end - begin;
      ProjectedBlock& pb = m.blocks[static_cast<size_t>(th)];
      for (size_t kb = begin; kb < end; kb += ProjectedBlock::kSize) {
        const int n = static_cast<int>(std::min<size_t>(ProjectedBlock::kSize, end - kb));
        pb.Project(R, t, &m.valid[kb], n, proj);
        for (int b = 0; b < n; ++b) {
          const int32_t jj = pb.pixel[b];
          if (jj < 0) continue;
          const size_t k = kb + static_cast<size_t>(b);
          const Eigen::Vector3f& v_s = m.valid[k].v;
          const Eigen::Vector3f q(pb.qx[b], pb.qy[b], pb.qz[b]);
          const size_t j = static_cast<size_t>(jj);
          if (!(model.range[j] > 0.0f)) continue;
          const Eigen::Vector3f& n_m = model.normal[j];
          const Eigen::Vector3f& v_m = model.vertex[j];
          const Eigen::Vector3f diff = q - v_m;
          if (diff.squaredNorm() > max_d2) continue;
          if (n_m.dot(R * m.valid[k].n) < min_cos) continue;
          Eigen::Matrix<float, 6, 1> J;
          const float r = PointToPlaneResidual<float>(R, t, v_s, v_m, n_m, &J);  // eq 15
          const float a = std::abs(r);
          const float w = (huber <= 0.0f || a <= huber) ? 1.0f : huber / a;
          acc.Add(J, r, w, v_s);
        }
      }
      acc.Flush();
    };
    m.pool.Run(job);
    for (const auto& acc : m.per_thread) acc.AddTo(eq);
  };
  return registration_internal::RunGaussNewton(s, T_model_scan_init, build);
}

}  // namespace slam_mms
