#include "slam_mms/surfel/surfel_map.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "core/option_error.hpp"
#include "surfel/fast_math.hpp"
#include "surfel/surfel_map_impl.hpp"
#include "surfel/surfel_projection_block.hpp"

namespace slam_mms {
namespace {

Status FieldError(const char* field, double value, const char* rule) {
  return internal::OptionError("SurfelMapOptions", field, value, rule);
}

}  // namespace

Status SurfelMapOptions::Validate() const {
  SLAM_MMS_RETURN_IF_ERROR(renderer.Validate().WithContext("SurfelMapOptions::renderer"));
  if (!(max_distance_m > 0.0)) return FieldError("max_distance_m", max_distance_m, "must be > 0");
  if (!(max_angle_deg > 0.0 && max_angle_deg <= 90.0)) {
    return FieldError("max_angle_deg", max_angle_deg, "must be in (0, 90]");
  }
  if (!(radius_factor > 0.0)) return FieldError("radius_factor", radius_factor, "must be > 0");
  if (!(min_radius_m > 0.0)) return FieldError("min_radius_m", min_radius_m, "must be > 0");
  if (!(max_radius_m >= min_radius_m)) {
    return FieldError("max_radius_m", max_radius_m, "must be >= min_radius_m");
  }
  if (!(min_radius_cos > 0.0 && min_radius_cos <= 1.0)) {
    return FieldError("min_radius_cos", min_radius_cos, "must be in (0, 1]");
  }
  if (!(min_creation_cos >= 0.0 && min_creation_cos < 1.0)) {
    return FieldError("min_creation_cos", min_creation_cos, "must be in [0, 1)");
  }
  if (!(p_stable > 0.5 && p_stable < 1.0)) {
    return FieldError("p_stable", p_stable, "must be in (0.5, 1)");
  }
  if (!(sigma_angle > 0.0)) return FieldError("sigma_angle", sigma_angle, "must be > 0");
  if (!(sigma_distance > 0.0)) return FieldError("sigma_distance", sigma_distance, "must be > 0");
  if (!std::isfinite(confidence_threshold)) {
    return FieldError("confidence_threshold", confidence_threshold, "must be finite");
  }
  if (unstable_age_frames < 0) {
    return FieldError("unstable_age_frames", unstable_age_frames, "must be >= 0");
  }
  if (!(max_confidence > 0.0)) return FieldError("max_confidence", max_confidence, "must be > 0");
  if (max_update_age_frames < 0) {
    return FieldError("max_update_age_frames", max_update_age_frames, "must be >= 0");
  }
  if (max_weight < 1) return FieldError("max_weight", max_weight, "must be >= 1");
  if (!(active_radius_m > 0.0))
    return FieldError("active_radius_m", active_radius_m, "must be > 0");
  if (!(index_cell_size_m > 0.1)) {
    return FieldError("index_cell_size_m", index_cell_size_m, "must be > 0.1");
  }
  return OkStatus();
}

SurfelMap::Impl::Impl(const SurfelMapOptions& o, int num_threads)
    : options(o),
      index(static_cast<float>(o.index_cell_size_m)),
      own_renderer(std::move(CpuSurfelRenderer::Create(o.renderer, num_threads).value())),
      pool(num_threads),
      removed_per_thread(static_cast<size_t>(num_threads)),
      moved_per_thread(static_cast<size_t>(num_threads)),
      integrated_per_thread(static_cast<size_t>(num_threads)),
      confirmed_per_thread(static_cast<size_t>(num_threads)),
      projection_blocks(static_cast<size_t>(num_threads)) {
  renderer = own_renderer.get();
}

uint32_t SurfelMap::Impl::AddSlot(const Surfel& s) {
  uint32_t id;
  if (!free_ids.empty()) {
    id = free_ids.back();
    free_ids.pop_back();
    surfels[id] = s;
    alive[id] = 1;
    conflict[id] = 0;
  } else {
    id = static_cast<uint32_t>(surfels.size());
    if (surfels.size() == surfels.capacity()) {
      // Grow by a quarter, not the vector's doubling: the slots are the map's largest block
      // (64 B a surfel), and doubling left up to half of it unused.
      surfels.reserve(surfels.size() + surfels.size() / 4 + 4096);
    }
    surfels.push_back(s);
    alive.push_back(1);
    conflict.push_back(0);
  }
  index.Insert(id, s.position);
  ++num_alive;
  return id;
}

void SurfelMap::Impl::RemoveSlot(uint32_t id) {
  if (!alive[id]) return;
  alive[id] = 0;
  index.Erase(id);
  free_ids.push_back(id);
  --num_alive;
}

SurfelMap::SurfelMap() : impl_(std::make_unique<Impl>(SurfelMapOptions(), 2)) {}
SurfelMap::SurfelMap(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SurfelMap::~SurfelMap() = default;
SurfelMap::SurfelMap(SurfelMap&&) noexcept = default;
SurfelMap& SurfelMap::operator=(SurfelMap&&) noexcept = default;

StatusOr<SurfelMap> SurfelMap::Create(const SurfelMapOptions& options, int num_threads) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (num_threads < 1 || num_threads > 64) {
    return internal::OptionError("SurfelMap::Create", "num_threads", num_threads,
                                 "must be in [1, 64]");
  }
  return SurfelMap(std::make_unique<Impl>(options, num_threads));
}

const SurfelMapOptions& SurfelMap::options() const { return impl_->options; }

Status SurfelMap::SetRenderer(SurfelRenderer* renderer) {
  if (renderer == nullptr) {
    impl_->renderer = impl_->own_renderer.get();
    return OkStatus();
  }
  const RangeProjectionOptions& a = renderer->projection().options();
  const RangeProjectionOptions& b = impl_->options.renderer.projection;
  if (a.rows != b.rows || a.cols != b.cols || a.fov_up_deg != b.fov_up_deg ||
      a.fov_down_deg != b.fov_down_deg || a.min_range_m != b.min_range_m ||
      a.max_range_m != b.max_range_m) {
    return InvalidArgumentError(
        "SurfelMap::SetRenderer: the renderer's projection (size, FOV, range gates) differs from "
        "SurfelMapOptions::renderer.projection");
  }
  impl_->renderer = renderer;
  return OkStatus();
}

SurfelRenderer& SurfelMap::renderer() { return *impl_->renderer; }
void SurfelMap::SetSubmapId(int32_t submap_id) { impl_->submap_id = submap_id; }
int32_t SurfelMap::submap_id() const { return impl_->submap_id; }
const std::vector<Surfel>& SurfelMap::surfels() const { return impl_->surfels; }
bool SurfelMap::IsAlive(uint32_t id) const {
  return id < impl_->alive.size() && impl_->alive[id] != 0;
}
size_t SurfelMap::size() const { return impl_->num_alive; }
int32_t SurfelMap::frame_count() const { return impl_->frame_count; }

std::vector<Surfel> SurfelMap::LiveSurfels() const {
  std::vector<Surfel> out;
  out.reserve(impl_->num_alive);
  for (size_t i = 0; i < impl_->surfels.size(); ++i) {
    if (impl_->alive[i]) out.push_back(impl_->surfels[i]);
  }
  return out;
}

size_t SurfelMap::MemoryBytes() const {
  const Impl& m = *impl_;
  size_t b = m.surfels.capacity() * sizeof(Surfel) + m.alive.capacity() + m.conflict.capacity() +
             m.free_ids.capacity() * sizeof(uint32_t) + m.index.MemoryBytes() +
             (m.active.capacity() + m.candidates.capacity()) * sizeof(uint32_t) +
             m.pixel_state.capacity();
  b += m.model.vertex.capacity() * sizeof(Eigen::Vector3f) * 2 +
       m.model.range.capacity() * sizeof(float) + m.model.index.capacity() * sizeof(int32_t);
  for (const auto& v : m.removed_per_thread) b += v.capacity() * sizeof(uint32_t);
  for (const auto& v : m.moved_per_thread) b += v.capacity() * sizeof(uint32_t);
  return b;
}

void SurfelMap::Clear() {
  Impl& m = *impl_;
  m.surfels.clear();
  m.alive.clear();
  m.conflict.clear();
  m.free_ids.clear();
  m.num_alive = 0;
  m.index.Clear();
  m.frame_count = 0;
}

namespace {

// Compacts ids[k0, k1) in place to the live surfels within r2 of c with confidence >
// min_confidence; returns how many were kept.
size_t KeepActive(const std::vector<Surfel>& surfels, const std::vector<uint8_t>& alive,
                  const Eigen::Vector3f& c, float r2, float min_confidence, size_t k0, size_t k1,
                  std::vector<uint32_t>* ids) {
  size_t kept = k0;
  constexpr size_t kPrefetch = 16;  // the candidates are scattered over the slots
  for (size_t k = k0; k < k1; ++k) {
    if (k + kPrefetch < k1) __builtin_prefetch(&surfels[(*ids)[k + kPrefetch]]);
    const uint32_t id = (*ids)[k];
    const Surfel& s = surfels[id];
    if (alive[id] && (s.position - c).squaredNorm() <= r2 && s.confidence > min_confidence) {
      (*ids)[kept++] = id;
    }
  }
  return kept - k0;
}

}  // namespace

void SurfelMap::SelectActive(const Eigen::Vector3d& center_world, double radius_m,
                             float min_confidence, std::vector<uint32_t>* ids) const {
  const Impl& m = *impl_;
  ids->clear();
  const Eigen::Vector3f c = center_world.cast<float>();
  const float r = static_cast<float>(radius_m);
  m.index.CandidatesInSphere(c, r, ids);
  ids->resize(KeepActive(m.surfels, m.alive, c, r * r, min_confidence, 0, ids->size(), ids));
}

void SurfelMap::SelectActive(const Eigen::Vector3d& center_world, double radius_m,
                             float min_confidence, std::vector<uint32_t>* ids) {
  Impl& m = *impl_;
  ids->clear();
  const Eigen::Vector3f c = center_world.cast<float>();
  const float r = static_cast<float>(radius_m);
  m.index.CandidatesInSphere(c, r, ids);
  const float r2 = r * r;
  const size_t n = ids->size();
  // Reading every candidate surfel is mostly cache misses: each thread compacts its part in
  // place, then the parts are joined in order (the ids of the serial filter, in its order).
  constexpr size_t kMinParallel = 16384;
  if (m.pool.num_threads() == 1 || n < kMinParallel) {
    ids->resize(KeepActive(m.surfels, m.alive, c, r2, min_confidence, 0, n, ids));
    return;
  }
  std::vector<size_t>& kept = m.kept_per_thread;
  kept.assign(static_cast<size_t>(m.pool.num_threads()), 0);
  m.pool.Run([&](int ti) {
    size_t k0 = 0;
    size_t k1 = 0;
    m.pool.Range(ti, n, &k0, &k1);
    kept[static_cast<size_t>(ti)] =
        KeepActive(m.surfels, m.alive, c, r2, min_confidence, k0, k1, ids);
  });
  size_t out = kept[0];
  for (int ti = 1; ti < m.pool.num_threads(); ++ti) {
    size_t k0 = 0;
    size_t k1 = 0;
    m.pool.Range(ti, n, &k0, &k1);
    const auto first = ids->begin() + static_cast<std::ptrdiff_t>(k0);
    if (out != k0)
      std::copy(first, first + static_cast<std::ptrdiff_t>(kept[static_cast<size_t>(ti)]),
                ids->begin() + static_cast<std::ptrdiff_t>(out));
    out += kept[static_cast<size_t>(ti)];
  }
  ids->resize(out);
}

Status SurfelMap::RenderModel(const Eigen::Isometry3d& T_world_sensor, float min_confidence,
                              VertexNormalMap* out) {
  Impl& m = *impl_;
  SelectActive(T_world_sensor.translation(), m.options.active_radius_m, min_confidence, &m.active);
  return m.renderer->Render(SurfelRenderInput::Subset(m.surfels, m.active), T_world_sensor, out);
}

size_t SurfelMap::TransformSubmap(int32_t submap_id, const Eigen::Isometry3d& T_new_old) {
  Impl& m = *impl_;
  const Eigen::Matrix3f R = T_new_old.linear().cast<float>();
  const Eigen::Vector3f t = T_new_old.translation().cast<float>();
  size_t n = 0;
  for (uint32_t id = 0; id < m.surfels.size(); ++id) {
    Surfel& s = m.surfels[id];
    if (!m.alive[id] || s.submap_id != submap_id) continue;
    TransformSurfel(R, t, &s);
    m.index.Update(id, s.position);
    ++n;
  }
  return n;
}

StatusOr<std::vector<uint32_t>> SurfelMap::AddSurfels(const std::vector<Surfel>& surfels) {
  for (size_t i = 0; i < surfels.size(); ++i) {
    const Surfel& s = surfels[i];
    if (!s.position.allFinite() || !s.normal.allFinite() || !std::isfinite(s.confidence) ||
        !(s.radius > 0.0f) || !std::isfinite(s.radius) ||
        std::abs(s.normal.norm() - 1.0f) > 1e-3f) {
      std::ostringstream os;
      os << "SurfelMap::AddSurfels: surfel " << i
         << " is invalid (non-finite values, radius <= 0 or normal not unit)";
      return InvalidArgumentError(os.str());
    }
  }
  std::vector<uint32_t> ids;
  ids.reserve(surfels.size());
  for (const Surfel& s : surfels) ids.push_back(impl_->AddSlot(s));
  return ids;
}

StatusOr<SurfelIntegrationStats> SurfelMap::Integrate(const VertexNormalMap& scan,
                                                      const Eigen::Isometry3d& T_world_sensor,
                                                      Timestamp stamp) {
  Impl& m = *impl_;
  const SurfelMapOptions& o = m.options;
  const RangeProjection& proj = m.renderer->projection();
  const int rows = proj.rows();
  const int cols = proj.cols();
  if (scan.rows != rows || scan.cols != cols ||
      scan.range.size() != static_cast<size_t>(rows) * static_cast<size_t>(cols) ||
      scan.vertex.size() != scan.range.size() || scan.normal.size() != scan.range.size()) {
    std::ostringstream os;
    os << "SurfelMap::Integrate: scan image is " << scan.rows << " x " << scan.cols
       << "; the map's projection is " << rows << " x " << cols;
    return InvalidArgumentError(os.str());
  }
  if (!T_world_sensor.matrix().allFinite()) {
    return InvalidArgumentError("SurfelMap::Integrate: T_world_sensor is not finite");
  }
  SurfelIntegrationStats stats;

  // 1-2. Active surfels and the model rendered at the pose.
  SelectActive(T_world_sensor.translation(), o.active_radius_m,
               -std::numeric_limits<float>::infinity(), &m.active);
  if (o.integrate_current_submap_only) {
    m.active.erase(
        std::remove_if(m.active.begin(), m.active.end(),
                       [&](uint32_t id) { return m.surfels[id].submap_id != m.submap_id; }),
        m.active.end());
  }
  stats.num_active = static_cast<int>(m.active.size());
  SLAM_MMS_RETURN_IF_ERROR(
      m.renderer->Render(SurfelRenderInput::Subset(m.surfels, m.active), T_world_sensor, &m.model));
  m.ClassifyPixels(scan, &stats);                              // 3.
  m.UpdateActiveSurfels(scan, T_world_sensor, stamp, &stats);  // 4-5.
  m.CreateSurfels(scan, T_world_sensor, stamp, &stats);        // 6.
  ++m.frame_count;
  stats.num_surfels = m.num_alive;
  return stats;
}

}  // namespace slam_mms
