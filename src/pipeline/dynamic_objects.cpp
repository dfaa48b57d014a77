#include "pipeline/dynamic_objects.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/option_error.hpp"

namespace slam_mms {

Status DynamicObjectOptions::Validate() const {
  auto bad = [](const char* field, double v, const char* rule) {
    return internal::OptionError("DynamicObjectOptions", field, v, rule);
  };
  if (min_object_pixels < 1) return bad("min_object_pixels", min_object_pixels, "must be >= 1");
  if (!(segmentation_angle_deg > 0.0 && segmentation_angle_deg < 90.0)) {
    return bad("segmentation_angle_deg", segmentation_angle_deg, "must be in (0, 90)");
  }
  if (!(ground_max_tilt_deg >= 0.0 && ground_max_tilt_deg < 90.0)) {
    return bad("ground_max_tilt_deg", ground_max_tilt_deg, "must be in [0, 90)");
  }
  if (!(min_residual_m > 0.0)) return bad("min_residual_m", min_residual_m, "must be > 0");
  if (!(residual_sigmas >= 0.0)) return bad("residual_sigmas", residual_sigmas, "must be >= 0");
  if (!(max_model_travel_m > 0.0)) {
    return bad("max_model_travel_m", max_model_travel_m, "must be > 0");
  }
  if (!(min_outlier_fraction > 0.0 && min_outlier_fraction <= 1.0)) {
    return bad("min_outlier_fraction", min_outlier_fraction, "must be in (0, 1]");
  }
  return OkStatus();
}

namespace internal {

namespace {

float Median(std::vector<float>* v) {
  if (v->empty()) return 0.0f;
  const auto mid = v->begin() + static_cast<std::ptrdiff_t>(v->size() / 2);
  std::nth_element(v->begin(), mid, v->end());
  return *mid;
}

}  // namespace

void TravelHistory::Add(int64_t stamp_ns, const Eigen::Vector3d& p_world, double keep_m) {
  if (!p_world.allFinite()) return;
  if (!stamps_.empty()) length_ += (p_world - last_).norm();
  last_ = p_world;
  stamps_.emplace_back(stamp_ns, length_);
  while (stamps_.size() > 2 && length_ - stamps_[1].second > keep_m) stamps_.pop_front();
}

int64_t TravelHistory::StampBefore(double travel_m) const {
  int64_t found = std::numeric_limits<int64_t>::min();
  for (const auto& [stamp, length] : stamps_) {
    if (length_ - length < travel_m) break;
    found = stamp;
  }
  return found;
}

DynamicObjectFilter::DynamicObjectFilter(const DynamicObjectOptions& options,
                                         const RangeProjection& projection,
                                         double max_correspondence_m, double max_angle_deg)
    : options_(options),
      projection_(projection),
      max_correspondence_m_(static_cast<float>(max_correspondence_m)),
      max_sin_(static_cast<float>(std::sin(max_angle_deg * M_PI / 180.0))) {}

void DynamicObjectFilter::Segment(const VertexNormalMap& scan, const Eigen::Vector3f& up_scan) {
  const int rows = scan.rows;
  const int cols = scan.cols;
  const int n = rows * cols;
  label_.assign(static_cast<size_t>(n), -1);
  num_labels_ = 0;
  const float ground_cos =
      static_cast<float>(std::cos(options_.ground_max_tilt_deg * M_PI / 180.0));
  auto joins = [&](int i) {
    if (!scan.HasVertex(i)) return false;
    return !(scan.HasNormal(i) &&
             std::abs(scan.normal[static_cast<size_t>(i)].dot(up_scan)) > ground_cos);
  };
  // Bogoslavskyi & Stachniss: neighbours at ranges d1 >= d2 separated by the angle alpha belong
  // together when atan2(d2 sin(alpha), d1 - d2 cos(alpha)) > theta.
  const RangeProjectionOptions& po = projection_.options();
  const float alpha_h = static_cast<float>(2.0 * M_PI / cols);
  const float alpha_v =
      static_cast<float>((po.fov_up_deg - po.fov_down_deg) * M_PI / 180.0 / std::max(rows, 1));
  const float tan_theta =
      static_cast<float>(std::tan(options_.segmentation_angle_deg * M_PI / 180));
  auto same = [&](int a, int b, float alpha) {
    const float ra = scan.range[static_cast<size_t>(a)];
    const float rb = scan.range[static_cast<size_t>(b)];
    const float d1 = std::max(ra, rb);
    const float d2 = std::min(ra, rb);
    const float den = d1 - d2 * std::cos(alpha);
    return den <= 0.0f || d2 * std::sin(alpha) > tan_theta * den;
  };
  for (int start = 0; start < n; ++start) {
    if (label_[static_cast<size_t>(start)] >= 0 || !joins(start)) continue;
    const int id = num_labels_++;
    queue_.clear();
    queue_.push_back(start);
    label_[static_cast<size_t>(start)] = id;
    for (size_t q = 0; q < queue_.size(); ++q) {
      const int i = queue_[q];
      const int r = i / cols;
      const int c = i % cols;
      const int nb[4] = {r > 0 ? i - cols : -1, r + 1 < rows ? i + cols : -1,
                         r * cols + (c + cols - 1) % cols, r * cols + (c + 1) % cols};
      for (int k = 0; k < 4; ++k) {
        const int j = nb[k];
        if (j < 0 || label_[static_cast<size_t>(j)] >= 0 || !joins(j)) continue;
        if (!same(i, j, k < 2 ? alpha_v : alpha_h)) continue;
        label_[static_cast<size_t>(j)] = id;
        queue_.push_back(j);
      }
    }
  }
}

DynamicObjectStats DynamicObjectFilter::Detect(const VertexNormalMap& scan,
                                               const VertexNormalMap& model,
                                               const Eigen::Vector3f& up_scan,
                                               const std::vector<Surfel>& surfels,
                                               int64_t min_created_ns) {
  DynamicObjectStats stats;
  const int n = scan.rows * scan.cols;
  mask_.assign(static_cast<size_t>(n), 0);
  seen_through_.clear();
  if (!options_.enabled || model.rows != scan.rows || model.cols != scan.cols || n == 0) {
    return stats;
  }
  Segment(scan, up_scan);

  // Point-to-plane residual of every scan pixel against the model pixel in the same place (both
  // images are for one pose; > 0: the scan point is in front of the model surface, < 0: behind
  // it, seen through it).
  residual_.assign(static_cast<size_t>(n), std::numeric_limits<float>::quiet_NaN());
  std::vector<float>& all = all_residuals_;
  all.clear();
  for (int i = 0; i < n; ++i) {
    const size_t k = static_cast<size_t>(i);
    if (!scan.HasNormal(i) || !model.HasVertex(i)) continue;
    const int32_t id = model.index[k];
    if (id < 0 || static_cast<size_t>(id) >= surfels.size() ||
        surfels[static_cast<size_t>(id)].created_ns < min_created_ns) {
      continue;
    }
    const Eigen::Vector3f d = scan.vertex[k] - model.vertex[k];
    const Eigen::Vector3f& n_model = model.normal[k];
    if (d.norm() > max_correspondence_m_) continue;
    if (scan.normal[k].cross(n_model).norm() > max_sin_) {
      continue;  // another surface: the registration does not pair them either
    }
    const float r = n_model.dot(d);
    residual_[k] = r;
    all.push_back(r);
  }
  if (all.empty()) return stats;
  // Robust scale of the residuals (MAD): a pose known less well raises the threshold.
  const float med = Median(&all);
  for (float& r : all) r = std::abs(r - med);
  const float sigma = 1.4826f * Median(&all);
  const float tau = std::max(static_cast<float>(options_.min_residual_m),
                             static_cast<float>(options_.residual_sigmas) * sigma);
  stats.threshold_m = tau;

  object_residuals_.resize(static_cast<size_t>(num_labels_));
  for (auto& v : object_residuals_) v.clear();
  for (int i = 0; i < n; ++i) {
    const int32_t l = label_[static_cast<size_t>(i)];
    const float r = residual_[static_cast<size_t>(i)];
    if (l >= 0 && std::isfinite(r)) object_residuals_[static_cast<size_t>(l)].push_back(r);
  }
  std::vector<int8_t>& moving = moving_;  // per object: +1 in front, -1 behind, 0 static
  moving.assign(static_cast<size_t>(num_labels_), 0);
  for (int l = 0; l < num_labels_; ++l) {
    std::vector<float>& v = object_residuals_[static_cast<size_t>(l)];
    if (static_cast<int>(v.size()) < options_.min_object_pixels) continue;
    ++stats.num_objects;
    const float m = Median(&v);
    if (!(std::abs(m) > tau)) continue;
    const size_t beyond = static_cast<size_t>(
        std::count_if(v.begin(), v.end(), [&](float r) { return m > 0.0f ? r > tau : r < -tau; }));
    if (static_cast<double>(beyond) < options_.min_outlier_fraction * v.size()) continue;
    moving[static_cast<size_t>(l)] = m > 0.0f ? 1 : -1;
    ++stats.num_moving;
  }
  if (stats.num_moving == 0) return stats;
  for (int i = 0; i < n; ++i) {
    const int32_t l = label_[static_cast<size_t>(i)];
    if (l < 0 || moving[static_cast<size_t>(l)] == 0) continue;
    mask_[static_cast<size_t>(i)] = 1;
    ++stats.num_masked_pixels;
    const float r = residual_[static_cast<size_t>(i)];
    if (moving[static_cast<size_t>(l)] < 0 && r < -tau) {
      const int32_t id = model.index[static_cast<size_t>(i)];
      if (id >= 0) seen_through_.push_back(static_cast<uint32_t>(id));
    }
  }
  std::sort(seen_through_.begin(), seen_through_.end());
  seen_through_.erase(std::unique(seen_through_.begin(), seen_through_.end()), seen_through_.end());
  return stats;
}

void DynamicObjectFilter::Apply(VertexNormalMap* scan) const {
  const size_t n = std::min(mask_.size(), static_cast<size_t>(scan->size()));
  for (size_t i = 0; i < n; ++i) {
    if (!mask_[i]) continue;
    scan->vertex[i].setZero();
    scan->normal[i].setZero();
    scan->range[i] = 0.0f;
    scan->index[i] = -1;
  }
}

size_t DynamicObjectFilter::MaskPoints(PointCloud* cloud) const {
  if (mask_.empty()) return 0;
  size_t masked = 0;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  ProjectedPoint px;
  for (Eigen::Vector3f& p : cloud->points()) {
    if (!projection_.Project(p, &px)) continue;
    if (mask_[static_cast<size_t>(px.row * projection_.cols() + px.col)]) {
      p.setConstant(nan);
      ++masked;
    }
  }
  return masked;
}

}  // namespace internal
}  // namespace slam_mms
