// SurfelMap::Integrate's stages after the model render (SuMa's map update): 3. classify the scan's
// pixels against the rendered model, 4-5. confirm/refine or penalise the active surfels and remove
// unstable ones, 6. create surfels for the unexplained pixels.
#include <algorithm>
#include <cmath>
#include <vector>

#include "surfel/surfel_map_impl.hpp"
#include "surfel/surfel_projection_block.hpp"

namespace slam_mms {

namespace {

// What stages 4-5 and 6 share: the sensor pose in float, the frame number, and the radius of a
// surfel seen at `range` under incidence cosine `cos_incidence` (SuMa: the pixel's footprint).
struct SensorFrame {
  SensorFrame(const SurfelMapOptions& options, const RangeProjection& proj,
              const Eigen::Isometry3d& T_world_sensor, int32_t frame_count)
      : o(options),
        R_ws(T_world_sensor.linear().cast<float>()),
        t_ws(T_world_sensor.translation().cast<float>()),
        frame(frame_count) {
    const RangeProjectionOptions& po = proj.options();
    const int rows = proj.rows();
    const int cols = proj.cols();
    pixel_size = static_cast<float>(
        std::max(std::tan(0.5 * (po.fov_up_deg - po.fov_down_deg) * M_PI / 180.0 / rows),
                 std::tan(M_PI / cols)));
    min_radius_cos = static_cast<float>(o.min_radius_cos);
  }
  float NewRadius(float range, float cos_incidence) const {
    const float c = std::clamp(cos_incidence, min_radius_cos, 1.0f);
    return std::clamp(static_cast<float>(o.radius_factor) * range * pixel_size / c,
                      static_cast<float>(o.min_radius_m), static_cast<float>(o.max_radius_m));
  }
  const SurfelMapOptions& o;
  Eigen::Matrix3f R_ws;
  Eigen::Vector3f t_ws;
  int32_t frame;
  float pixel_size = 0.0f;
  float min_radius_cos = 0.0f;
};

}  // namespace

void SurfelMap::Impl::ClassifyPixels(const VertexNormalMap& scan, SurfelIntegrationStats* out) {
  Impl& m = *this;
  const SurfelMapOptions& o = options;
  const RangeProjection& proj = renderer->projection();
  const int rows = proj.rows();
  const int cols = proj.cols();
  const float max_d = static_cast<float>(o.max_distance_m);
  const float max_sin = static_cast<float>(std::sin(o.max_angle_deg * M_PI / 180.0));
  const int num_pixels = rows * cols;
  m.pixel_state.resize(static_cast<size_t>(num_pixels));
  const int num_threads = m.pool.num_threads();

  // 3. Per pixel: explained by the rendered surfel, or a conflict (the ray passed through it).
  const int pix_chunk = (num_pixels + num_threads - 1) / num_threads;
  m.pool.Run([&](int ti) {
    const int i0 = std::min(num_pixels, ti * pix_chunk);
    const int i1 = std::min(num_pixels, i0 + pix_chunk);
    for (int i = i0; i < i1; ++i) {
      uint8_t state = kNone;
      if (scan.HasVertex(i) && m.model.HasVertex(i)) {
        const Eigen::Vector3f& ns = m.model.normal[i];
        const float d = std::abs(ns.dot(scan.vertex[i] - m.model.vertex[i]));
        if (scan.HasNormal(i) && d < max_d && scan.normal[i].cross(ns).norm() < max_sin) {
          state = kExplained;
        } else if (scan.range[i] > m.model.range[i] + max_d) {
          state = kConflict;
        }
      }
      m.pixel_state[i] = state;
    }
  });
  std::vector<uint32_t>& conflicted = m.candidates;  // reuse as the list of flagged ids
  conflicted.clear();
  for (int i = 0; i < num_pixels; ++i) {
    if (m.pixel_state[i] == kExplained) ++out->num_explained;
    if (m.pixel_state[i] != kConflict) continue;
    const uint32_t id = static_cast<uint32_t>(m.model.index[i]);
    if (!m.conflict[id]) {
      m.conflict[id] = 1;
      conflicted.push_back(id);
    }
  }
  out->num_conflicts = static_cast<int>(conflicted.size());
}

void SurfelMap::Impl::UpdateActiveSurfels(const VertexNormalMap& scan,
                                          const Eigen::Isometry3d& T_world_sensor, Timestamp stamp,
                                          SurfelIntegrationStats* out) {
  Impl& m = *this;
  const SurfelMapOptions& o = options;
  const RangeProjection& proj = renderer->projection();
  const int rows = proj.rows();
  const int cols = proj.cols();
  const SensorFrame f(o, proj, T_world_sensor, frame_count);
  const int32_t frame = f.frame;
  const Eigen::Matrix3f& R_ws = f.R_ws;
  const Eigen::Vector3f& t_ws = f.t_ws;
  const RangeProjectionOptions& po = proj.options();
  const float max_d = static_cast<float>(o.max_distance_m);
  const float max_sin = static_cast<float>(std::sin(o.max_angle_deg * M_PI / 180.0));
  const int num_threads = pool.num_threads();
  const Eigen::Isometry3d T_sensor_world = T_world_sensor.inverse();
  const Eigen::Matrix3f R_sw = T_sensor_world.linear().cast<float>();
  const Eigen::Vector3f t_sw = T_sensor_world.translation().cast<float>();
  const float fov_up = static_cast<float>(po.fov_up_deg * M_PI / 180.0);
  const float rows_per_rad =
      static_cast<float>(rows / ((po.fov_up_deg - po.fov_down_deg) * M_PI / 180.0));
  const float log_unstable = static_cast<float>(std::log((1.0 - o.p_stable) / o.p_stable));
  const float inv_sa2 = static_cast<float>(1.0 / (o.sigma_angle * o.sigma_angle));
  const float inv_sd2 = static_cast<float>(1.0 / (o.sigma_distance * o.sigma_distance));
  const float p_stable = static_cast<float>(o.p_stable);
  const float max_conf = static_cast<float>(o.max_confidence);
  const float conf_threshold = static_cast<float>(o.confidence_threshold);
  const float min_r = static_cast<float>(po.min_range_m);
  const float max_r = static_cast<float>(po.max_range_m);
  const size_t n_active = m.active.size();
  const size_t chunk = (n_active + static_cast<size_t>(num_threads) - 1) / num_threads;
  m.pool.Run([&](int ti) {
    std::vector<uint32_t>& removed = m.removed_per_thread[static_cast<size_t>(ti)];
    std::vector<uint32_t>& moved = m.moved_per_thread[static_cast<size_t>(ti)];
    std::vector<int>& integrated = m.integrated_per_thread[static_cast<size_t>(ti)];
    removed.clear();
    moved.clear();
    integrated.clear();
    int confirmed = 0;
    const size_t k0 = std::min(n_active, static_cast<size_t>(ti) * chunk);
    const size_t k1 = std::min(n_active, k0 + chunk);
    internal::SurfelProjectionBlock& pb = m.projection_blocks[static_cast<size_t>(ti)];
    for (size_t kb = k0; kb < k1; kb += internal::SurfelProjectionBlock::kSize) {
      const int nb =
          static_cast<int>(std::min<size_t>(internal::SurfelProjectionBlock::kSize, k1 - kb));
      pb.Project(m.surfels.data(), &m.active[kb], nb, k1 - kb, R_sw, t_sw, min_r, max_r, fov_up,
                 rows_per_rad, static_cast<float>(cols));
      for (int b = 0; b < nb; ++b) {
        const size_t k = kb + static_cast<size_t>(b);
        const uint32_t id = m.active[k];
        Surfel& s = m.surfels[id];
        const Eigen::Vector3f p(pb.px[b], pb.py[b], pb.pz[b]);
        const Eigen::Vector3f n(pb.nx[b], pb.ny[b], pb.nz[b]);
        bool is_confirmed = false;
        if (pb.in_range[b]) {
          const float v = pb.v[b];
          float u = pb.u[b];
          const int row = static_cast<int>(std::floor(v));
          int col = static_cast<int>(std::floor(u));
          if (col >= cols) col -= cols;
          if (col < 0) col += cols;
          if (row >= 0 && row < rows) {
            const int i = row * cols + col;
            if (scan.HasVertex(i) && scan.HasNormal(i)) {
              const Eigen::Vector3f& vm = scan.vertex[i];
              const Eigen::Vector3f& nm = scan.normal[i];
              const float dist = std::abs(n.dot(vm - p));
              const float a = nm.cross(n).norm();
              if (dist < max_d && a < max_sin) {
                is_confirmed = true;
                float prob =
                    p_stable * std::exp(-a * a * inv_sa2) * std::exp(-dist * dist * inv_sd2);
                prob = std::clamp(prob, 1.0f - p_stable, 0.999f);
                s.confidence = std::min(s.confidence + std::log(prob / (1.0f - prob)), max_conf);
                const float range = scan.range[i];
                s.radius = std::min(s.radius, f.NewRadius(range, -nm.dot(vm) / range));
                if (frame - s.created_frame < o.max_update_age_frames) {
                  const float w = static_cast<float>(std::min(s.num_updates + 1, o.max_weight));
                  const Eigen::Vector3f v_world = R_ws * vm + t_ws;
                  const Eigen::Vector3f n_world = R_ws * nm;
                  const Eigen::Vector3f old_position = s.position;
                  s.position = (w * s.position + v_world) / (w + 1.0f);
                  const Eigen::Vector3f nn = w * s.normal + n_world;
                  const float len = nn.norm();
                  if (len > 1e-6f) s.normal = nn / len;
                  if (!m.index.SameCell(old_position, s.position)) moved.push_back(id);
                }
                s.updated_frame = frame;
                s.updated_ns = stamp.nanoseconds();
                ++s.num_updates;
                ++confirmed;
                integrated.push_back(i);  // SuMa: the pixel is integrated, no new surfel there
              }
            }
          }
        }
        if (!is_confirmed && m.conflict[id]) s.confidence += log_unstable;
        m.conflict[id] = 0;
        if (s.confidence < log_unstable ||
            (s.confidence <= conf_threshold && frame - s.updated_frame >= o.unstable_age_frames)) {
          removed.push_back(id);
        }
      }
    }
    m.confirmed_per_thread[static_cast<size_t>(ti)] = confirmed;
  });
  for (int c : m.confirmed_per_thread) out->num_confirmed += c;
  for (const auto& integrated : m.integrated_per_thread) {
    for (int i : integrated) m.pixel_state[static_cast<size_t>(i)] = kExplained;
  }
  for (const auto& removed : m.removed_per_thread) {
    for (uint32_t id : removed) m.RemoveSlot(id);
    out->num_removed += static_cast<int>(removed.size());
  }
  for (const auto& moved : m.moved_per_thread) {
    for (uint32_t id : moved) {
      if (m.alive[id]) m.index.Update(id, m.surfels[id].position);
    }
  }
}

void SurfelMap::Impl::CreateSurfels(const VertexNormalMap& scan,
                                    const Eigen::Isometry3d& T_world_sensor, Timestamp stamp,
                                    SurfelIntegrationStats* out) {
  Impl& m = *this;
  const SurfelMapOptions& o = options;
  const RangeProjection& proj = renderer->projection();
  const int rows = proj.rows();
  const int cols = proj.cols();
  const SensorFrame f(o, proj, T_world_sensor, frame_count);
  const int32_t frame = f.frame;
  const Eigen::Matrix3f& R_ws = f.R_ws;
  const Eigen::Vector3f& t_ws = f.t_ws;
  const int num_pixels = rows * cols;
  const float min_cos = static_cast<float>(o.min_creation_cos);
  for (int i = 0; i < num_pixels; ++i) {
    if (m.pixel_state[i] == kExplained || !scan.HasVertex(i) || !scan.HasNormal(i)) continue;
    const Eigen::Vector3f& v = scan.vertex[i];
    const Eigen::Vector3f& nv = scan.normal[i];
    const float range = scan.range[i];
    const float cos_inc = -nv.dot(v) / range;
    if (!(cos_inc > min_cos)) continue;
    Surfel s;
    s.position = R_ws * v + t_ws;
    s.normal = (R_ws * nv).normalized();
    s.radius = f.NewRadius(range, cos_inc);
    s.confidence = 0.0f;  // log-odds of the prior p = 0.5
    s.created_ns = s.updated_ns = stamp.nanoseconds();
    s.created_frame = s.updated_frame = frame;
    s.submap_id = m.submap_id;
    s.num_updates = 0;
    m.AddSlot(s);
    ++out->num_created;
  }
}

}  // namespace slam_mms
