#include "slam_mms/surfel/range_projection.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/option_error.hpp"

namespace slam_mms {
namespace {

constexpr double kPi = 3.14159265358979323846;

Status FieldError(const char* field, double value, const char* rule) {
  return internal::OptionError("RangeProjectionOptions", field, value, rule);
}

}  // namespace

Status RangeProjectionOptions::Validate() const {
  if (rows <= 0) return FieldError("rows", rows, "must be > 0");
  if (cols <= 0) return FieldError("cols", cols, "must be > 0");
  if (static_cast<long long>(rows) * cols > (1LL << 26)) {
    return FieldError("rows * cols", static_cast<double>(rows) * cols, "must be <= 2^26");
  }
  if (!(fov_up_deg <= 90.0 && fov_up_deg > -90.0)) {
    return FieldError("fov_up_deg", fov_up_deg, "must be in (-90, 90]");
  }
  if (!(fov_down_deg >= -90.0 && fov_down_deg < fov_up_deg)) {
    return FieldError("fov_down_deg", fov_down_deg, "must be in [-90, fov_up_deg)");
  }
  if (!(min_range_m >= 0.0)) return FieldError("min_range_m", min_range_m, "must be >= 0");
  if (!(max_range_m > min_range_m) || !std::isfinite(max_range_m)) {
    return FieldError("max_range_m", max_range_m, "must be finite and > min_range_m");
  }
  if (!(normal_max_range_jump_m >= 0.0)) {
    return FieldError("normal_max_range_jump_m", normal_max_range_jump_m, "must be >= 0");
  }
  if (normal_col_step < 1) return FieldError("normal_col_step", normal_col_step, "must be >= 1");
  if (!(normal_max_range_jump_ratio >= 0.0)) {
    return FieldError("normal_max_range_jump_ratio", normal_max_range_jump_ratio, "must be >= 0");
  }
  return OkStatus();
}

RangeProjection::RangeProjection() : RangeProjection(RangeProjectionOptions()) {}

StatusOr<RangeProjection> RangeProjection::Create(const RangeProjectionOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  return RangeProjection(options);
}

RangeProjection::RangeProjection(const RangeProjectionOptions& options) : options_(options) {
  fov_up_rad_ = static_cast<float>(options_.fov_up_deg * kPi / 180.0);
  fov_rad_ = static_cast<float>((options_.fov_up_deg - options_.fov_down_deg) * kPi / 180.0);
  const int rows = options_.rows;
  const int cols = options_.cols;
  ray_directions_.resize(static_cast<size_t>(rows) * static_cast<size_t>(cols));
  const double fov_up = options_.fov_up_deg * kPi / 180.0;
  const double fov = (options_.fov_up_deg - options_.fov_down_deg) * kPi / 180.0;
  row_cos_.resize(static_cast<size_t>(rows));
  row_sin_.resize(static_cast<size_t>(rows));
  col_cos_.resize(static_cast<size_t>(cols));
  col_sin_.resize(static_cast<size_t>(cols));
  for (int r = 0; r < rows; ++r) {
    const double pitch = fov_up - (r + 0.5) / rows * fov;
    row_cos_[static_cast<size_t>(r)] = static_cast<float>(std::cos(pitch));
    row_sin_[static_cast<size_t>(r)] = static_cast<float>(std::sin(pitch));
  }
  for (int c = 0; c < cols; ++c) {
    const double yaw = kPi * (1.0 - 2.0 * (c + 0.5) / cols);
    col_cos_[static_cast<size_t>(c)] = static_cast<float>(std::cos(yaw));
    col_sin_[static_cast<size_t>(c)] = static_cast<float>(std::sin(yaw));
  }
  for (int r = 0; r < rows; ++r) {
    const float cp = row_cos_[static_cast<size_t>(r)];
    const float sp = row_sin_[static_cast<size_t>(r)];
    for (int c = 0; c < cols; ++c) {
      ray_directions_[static_cast<size_t>(r * cols + c)] = Eigen::Vector3f(
          cp * col_cos_[static_cast<size_t>(c)], cp * col_sin_[static_cast<size_t>(c)], sp);
    }
  }
}

bool RangeProjection::ProjectDirection(const Eigen::Vector3f& p, float* u, float* v) const {
  const float r = p.norm();
  if (!(r > 0.0f) || !std::isfinite(r)) return false;
  const float yaw = std::atan2(p.y(), p.x());
  const float pitch = std::asin(std::clamp(p.z() / r, -1.0f, 1.0f));
  const float cols = static_cast<float>(options_.cols);
  const float rows = static_cast<float>(options_.rows);
  float uu = 0.5f * (1.0f - yaw / static_cast<float>(kPi)) * cols;
  if (uu >= cols) uu -= cols;
  if (uu < 0.0f) uu += cols;
  const float vv = (fov_up_rad_ - pitch) / fov_rad_ * rows;
  if (!(vv >= 0.0f && vv < rows)) return false;
  *u = uu;
  *v = vv;
  return true;
}

bool RangeProjection::Project(const Eigen::Vector3f& p_sensor, ProjectedPoint* out) const {
  const float r = p_sensor.norm();
  if (!std::isfinite(r) || r < static_cast<float>(options_.min_range_m) ||
      r > static_cast<float>(options_.max_range_m) || !(r > 0.0f)) {
    return false;
  }
  float u = 0.0f;
  float v = 0.0f;
  if (!ProjectDirection(p_sensor, &u, &v)) return false;
  out->u = u;
  out->v = v;
  out->range = r;
  out->col = std::min(static_cast<int>(u), options_.cols - 1);
  out->row = std::min(static_cast<int>(v), options_.rows - 1);
  return true;
}

Eigen::Vector3f RangeProjection::Unproject(float u, float v, float range) const {
  const double yaw = kPi * (1.0 - 2.0 * static_cast<double>(u) / options_.cols);
  const double pitch = static_cast<double>(fov_up_rad_) -
                       static_cast<double>(v) / options_.rows * static_cast<double>(fov_rad_);
  const double cp = std::cos(pitch);
  return (static_cast<double>(range) *
          Eigen::Vector3d(cp * std::cos(yaw), cp * std::sin(yaw), std::sin(pitch)))
      .cast<float>();
}

void RangeProjection::ComputeVertexMap(const PointCloudView& cloud, VertexNormalMap* out) const {
  out->Reset(options_.rows, options_.cols);
  ProjectedPoint px;
  for (size_t i = 0; i < cloud.size; ++i) {
    const Eigen::Vector3f p = cloud.Point(i);
    if (!p.allFinite() || !Project(p, &px)) continue;
    const int k = out->PixelIndex(px.row, px.col);
    float& r = out->range[static_cast<size_t>(k)];
    if (r > 0.0f && r <= px.range) continue;  // nearest point wins
    r = px.range;
    out->vertex[static_cast<size_t>(k)] = p;
    out->index[static_cast<size_t>(k)] = static_cast<int32_t>(i);
  }
}

void RangeProjection::ComputeNormals(VertexNormalMap* map) const {
  ComputeNormals(map, 0, map->rows);
}

void RangeProjection::ComputeNormals(VertexNormalMap* map, int row_begin, int row_end) const {
  const int rows = map->rows;
  const int cols = map->cols;
  const float jump_m = static_cast<float>(options_.normal_max_range_jump_m);
  const float jump_ratio = static_cast<float>(options_.normal_max_range_jump_ratio);
  const int col_step = std::max(1, options_.normal_col_step);
  row_begin = std::max(row_begin, 0);
  row_end = std::min(row_end, rows);
  for (int row = row_begin; row < row_end; ++row) {
    for (int col = 0; col < cols; ++col) {
      const int k = row * cols + col;
      map->normal[static_cast<size_t>(k)].setZero();
      const float r = map->range[static_cast<size_t>(k)];
      if (!(r > 0.0f)) continue;
      const float max_jump = std::max(jump_m, jump_ratio * r);
      auto usable = [&](int kn) {
        if (kn < 0) return false;
        const float rn = map->range[static_cast<size_t>(kn)];
        return rn > 0.0f && std::abs(rn - r) <= max_jump;
      };
      // Central difference where both neighbours pass the discontinuity test, else one-sided.
      auto difference = [&](int k_plus, int k_minus, Eigen::Vector3f* d) {
        const bool plus = usable(k_plus);
        const bool minus = usable(k_minus);
        const Eigen::Vector3f& p = map->vertex[static_cast<size_t>(k)];
        if (plus && minus) {
          *d = map->vertex[static_cast<size_t>(k_plus)] - map->vertex[static_cast<size_t>(k_minus)];
        } else if (plus) {
          *d = map->vertex[static_cast<size_t>(k_plus)] - p;
        } else if (minus) {
          *d = p - map->vertex[static_cast<size_t>(k_minus)];
        } else {
          return false;
        }
        return true;
      };
      const int step = std::min(col_step, cols / 2);
      const int right = row * cols + (col + step) % cols;
      const int left = row * cols + (col - step + cols) % cols;
      const int up = row > 0 ? k - cols : -1;
      const int down = row + 1 < rows ? k + cols : -1;
      Eigen::Vector3f dh, dv;
      if (!difference(right, left, &dh) || !difference(down, up, &dv)) continue;
      const Eigen::Vector3f& p = map->vertex[static_cast<size_t>(k)];
      const float nh = dh.norm();
      const float nv = dv.norm();
      if (!(nh > 1e-6f) || !(nv > 1e-6f)) continue;
      Eigen::Vector3f n = (dh / nh).cross(dv / nv);
      const float len = n.norm();
      if (!(len > 1e-3f)) continue;  // (nearly) collinear neighbours
      n /= len;
      if (n.dot(p) > 0.0f) n = -n;  // towards the sensor
      map->normal[static_cast<size_t>(k)] = n;
    }
  }
}

void RangeProjection::ComputeVertexNormalMap(const PointCloudView& cloud,
                                             VertexNormalMap* out) const {
  ComputeVertexMap(cloud, out);
  ComputeNormals(out);
}

}  // namespace slam_mms
