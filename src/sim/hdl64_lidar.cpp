// Hdl64Lidar: per-firing ray casting along the true trajectory.
#include "slam_mms/sim/hdl64_lidar.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <thread>

#include "sim/random.hpp"

namespace slam_mms::sim {
namespace {

// Counter-based uniform in (0, 1) from a 64-bit key.
double HashUniform(uint64_t key) {
  return (static_cast<double>(MixSeed(key, 0x51ED) >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}
double HashNormal(uint64_t key) {
  const double u1 = HashUniform(key), u2 = HashUniform(key ^ 0xA5A5A5A5A5A5A5A5ULL);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

// A depth edge beside (b, f): a neighbour (the ring's previous or next firing, or the previous
// or next ring at the same firing) whose range differs by more than threshold + 2 % of the range
// and whose point lies off this point's tangent plane by more than 0.1 m + 0.5 % of the range
// (so that a smooth surface seen at a slant, like the ground between rings, is no edge).
bool IsDepthEdge(const std::vector<float>& r, const std::vector<Eigen::Vector3f>& p,
                 const std::vector<Eigen::Vector3f>& n, int nb, int nf, int b, int f,
                 double threshold) {
  const size_t i0 = static_cast<size_t>(b) * nf + f;
  const float r0 = r[i0];
  const double limit = threshold + 0.02 * r0, plane = 0.1 + 0.005 * r0;
  auto differs = [&](int bb, int ff) {
    if (bb < 0 || bb >= nb || ff < 0 || ff >= nf) return false;
    const size_t i = static_cast<size_t>(bb) * nf + ff;
    return r[i] > 0.f && std::abs(r[i] - r0) > limit && std::abs(n[i0].dot(p[i] - p[i0])) > plane;
  };
  return differs(b, f - 1) || differs(b, f + 1) || differs(b - 1, f) || differs(b + 1, f);
}

}  // namespace

// One echo of a footprint sample: range, albedo, |cos incidence|, class.
struct Hdl64Lidar::Echo {
  double range;
  double albedo;
  double cos_inc;
  SurfaceClass surface;
};

void Hdl64Lidar::MergeEchoes(Echo* echoes, int n, int num_samples, double max_separation_m,
                             double* range, double* shaded, SurfaceClass* surface) {
  // Echo energy ~ albedo |cos| / r^2 per sample. Groups: sorted by range, an echo joins the group
  // of the nearest one while within max_separation_m of the group's first echo. The group with
  // the most energy is the return: its energy-weighted mean range, its share of the footprint's
  // shaded reflectance, the class of its strongest echo.
  for (int i = 1; i < n; ++i) {  // insertion sort by range (n <= 7)
    const Echo x = echoes[i];
    int j = i;
    for (; j > 0 && echoes[j - 1].range > x.range; --j) echoes[j] = echoes[j - 1];
    echoes[j] = x;
  }
  double best_energy = -1.0;
  for (int i = 0; i < n;) {
    int j = i;
    double e_sum = 0.0, er_sum = 0.0, s_sum = 0.0, e_max = -1.0;
    SurfaceClass cls = echoes[i].surface;
    while (j < n && echoes[j].range - echoes[i].range <= max_separation_m) {
      const Echo& x = echoes[j];
      const double e = x.albedo * x.cos_inc / std::max(1e-2, x.range * x.range) + 1e-12;
      e_sum += e;
      er_sum += e * x.range;
      s_sum += x.albedo * (0.3 + 0.7 * x.cos_inc);
      if (e > e_max) {
        e_max = e;
        cls = x.surface;
      }
      ++j;
    }
    if (e_sum > best_energy) {
      best_energy = e_sum;
      *range = er_sum / e_sum;
      *shaded = s_sum / num_samples;
      *surface = cls;
    }
    i = j;
  }
}

Status Hdl64Lidar::Options::Validate() const {
  auto fail = [](const char* name, double v, const char* rule) {
    std::ostringstream s;
    s << "Hdl64Lidar::Options::" << name << " = " << v << "; " << rule;
    return InvalidArgumentError(s.str());
  };
  if (elevation_table_deg.empty()) {
    if (num_beams < 1 || num_beams > 256)
      return fail("num_beams", num_beams, "must be in [1, 256]");
    if (!(elevation_max_deg > elevation_min_deg) && num_beams > 1)
      return fail("elevation_max_deg", elevation_max_deg, "must be > elevation_min_deg");
  } else if (elevation_table_deg.size() > 256) {
    return fail("elevation_table_deg.size()", static_cast<double>(elevation_table_deg.size()),
                "must be <= 256");
  }
  if (firings_per_revolution < 8)
    return fail("firings_per_revolution", firings_per_revolution, "must be >= 8");
  if (!(rotation_rate_hz > 0.0)) return fail("rotation_rate_hz", rotation_rate_hz, "must be > 0");
  if (!(range_noise_sigma_m >= 0.0))
    return fail("range_noise_sigma_m", range_noise_sigma_m, "must be >= 0");
  if (!(min_range_m >= 0.0)) return fail("min_range_m", min_range_m, "must be >= 0");
  if (!(max_range_m > min_range_m))
    return fail("max_range_m", max_range_m, "must be > min_range_m");
  if (!(min_cos_incidence >= 0.0 && min_cos_incidence < 1.0))
    return fail("min_cos_incidence", min_cos_incidence, "must be in [0, 1)");
  if (!(reflectance_noise_sigma >= 0.0))
    return fail("reflectance_noise_sigma", reflectance_noise_sigma, "must be >= 0");
  if (!(dropout_base >= 0.0 && dropout_base < 1.0))
    return fail("dropout_base", dropout_base, "must be in [0, 1)");
  if (!(dropout_far >= 0.0 && dropout_far <= 1.0))
    return fail("dropout_far", dropout_far, "must be in [0, 1]");
  if (!(std::abs(elevation_bias_deg) < 5.0))
    return fail("elevation_bias_deg", elevation_bias_deg, "must be in (-5, 5)");
  if (!(laser_elevation_sigma_deg >= 0.0 && laser_elevation_sigma_deg <= 1.0))
    return fail("laser_elevation_sigma_deg", laser_elevation_sigma_deg, "must be in [0, 1]");
  if (!(laser_azimuth_sigma_deg >= 0.0 && laser_azimuth_sigma_deg <= 1.0))
    return fail("laser_azimuth_sigma_deg", laser_azimuth_sigma_deg, "must be in [0, 1]");
  if (!(laser_range_offset_sigma_m >= 0.0 && laser_range_offset_sigma_m <= 0.5))
    return fail("laser_range_offset_sigma_m", laser_range_offset_sigma_m, "must be in [0, 0.5]");
  if (!(laser_range_scale_sigma >= 0.0 && laser_range_scale_sigma <= 0.05))
    return fail("laser_range_scale_sigma", laser_range_scale_sigma, "must be in [0, 0.05]");
  if (!(beam_divergence_rad >= 0.0 && beam_divergence_rad <= 0.02))
    return fail("beam_divergence_rad", beam_divergence_rad, "must be in [0, 0.02]");
  if (!(mixed_pixel_max_separation_m >= 0.0))
    return fail("mixed_pixel_max_separation_m", mixed_pixel_max_separation_m, "must be >= 0");
  if (!(mixed_pixel_edge_threshold_m > 0.0))
    return fail("mixed_pixel_edge_threshold_m", mixed_pixel_edge_threshold_m, "must be > 0");
  return OkStatus();
}

void Hdl64Lidar::Options::EnableLaserIntrinsicErrors() {
  laser_elevation_sigma_deg = 0.03;
  laser_azimuth_sigma_deg = 0.03;
  laser_range_offset_sigma_m = 0.02;
  laser_range_scale_sigma = 1e-3;
}

std::vector<Hdl64Lidar::LaserError> Hdl64Lidar::LaserErrors(uint64_t seed) const {
  std::vector<LaserError> e(elevations_deg_.size());
  const Options& o = options_;
  if (o.laser_elevation_sigma_deg == 0.0 && o.laser_azimuth_sigma_deg == 0.0 &&
      o.laser_range_offset_sigma_m == 0.0 && o.laser_range_scale_sigma == 0.0) {
    return e;
  }
  Rng rng(MixSeed(seed, 0x1A5E7));
  for (LaserError& l : e) {
    l.elevation_deg = rng.Normal(o.laser_elevation_sigma_deg);
    l.azimuth_deg = rng.Normal(o.laser_azimuth_sigma_deg);
    l.range_offset_m = rng.Normal(o.laser_range_offset_sigma_m);
    l.range_scale = rng.Normal(o.laser_range_scale_sigma);
  }
  return e;
}

Hdl64Lidar::Hdl64Lidar() : Hdl64Lidar(Options()) {}

Hdl64Lidar::Hdl64Lidar(const Options& options) : options_(options) {
  if (!options_.elevation_table_deg.empty()) {
    elevations_deg_ = options_.elevation_table_deg;
  } else {
    const int n = options_.num_beams;
    for (int b = 0; b < n; ++b) {
      elevations_deg_.push_back(
          n == 1 ? options_.elevation_max_deg
                 : options_.elevation_max_deg +
                       (options_.elevation_min_deg - options_.elevation_max_deg) * b / (n - 1));
    }
  }
}

double Hdl64Lidar::LastFiringOffsetSeconds() const {
  return (options_.firings_per_revolution - 1) /
         (options_.firings_per_revolution * options_.rotation_rate_hz);
}

Hdl64Lidar::Output Hdl64Lidar::Simulate(const CityWorld& world,
                                        const ReferenceTrajectory& trajectory,
                                        const Eigen::Isometry3d& T_body_lidar, double t_start_s,
                                        int64_t scan_index, uint64_t seed, int num_threads) const {
  const int nb = static_cast<int>(elevations_deg_.size());
  const int nf = options_.firings_per_revolution;
  const double firing_dt = 1.0 / (nf * options_.rotation_rate_hz);
  const double deg = M_PI / 180.0;
  const std::vector<LaserError> laser = LaserErrors(seed);
  // True beam directions (nominal + residual) for casting; written directions (nominal - bias).
  std::vector<double> cos_el(nb), sin_el(nb), cos_el_w(nb), sin_el_w(nb), cos_daz(nb), sin_daz(nb);
  for (int b = 0; b < nb; ++b) {
    const double el_true = (elevations_deg_[b] + laser[b].elevation_deg) * deg;
    cos_el[b] = std::cos(el_true);
    sin_el[b] = std::sin(el_true);
    const double written = (elevations_deg_[b] - options_.elevation_bias_deg) * deg;
    cos_el_w[b] = std::cos(written);
    sin_el_w[b] = std::sin(written);
    cos_daz[b] = std::cos(laser[b].azimuth_deg * deg);
    sin_daz[b] = std::sin(laser[b].azimuth_deg * deg);
  }
  // Pass 1 per (beam, firing): the noise-free return of the beam's centre ray (hit_range < 0 = no
  // return). Pass 2: mixed pixels, calibration residuals, noise, dropouts -> range (< 0 = none).
  const size_t total = static_cast<size_t>(nb) * nf;
  std::vector<float> hit_range(total, -1.f), hit_cos(total, 0.f), hit_albedo(total, 0.f);
  std::vector<uint8_t> hit_volume(total, 0);  // a return from inside a scattering volume
  std::vector<float> range(total, -1.f), refl(total, 0.f);
  std::vector<Eigen::Vector3f> p_world(total), n_world(total);
  std::vector<SurfaceClass> surf(total, SurfaceClass::kOther);
  const uint64_t scan_key = MixSeed(seed, 0x11DA5 + static_cast<uint64_t>(scan_index));
  auto ray_key = [&](int b, int f) {
    return scan_key ^ (static_cast<uint64_t>(b) << 40) ^ static_cast<uint64_t>(f);
  };
  // Beam direction in the lidar frame (true, with the residuals) and its footprint axes.
  auto beam_dir = [&](int b, double ca, double sa, Eigen::Vector3d* e_az, Eigen::Vector3d* e_el) {
    const double c = ca * cos_daz[b] - sa * sin_daz[b], s = sa * cos_daz[b] + ca * sin_daz[b];
    if (e_az != nullptr) {
      *e_az = Eigen::Vector3d(-s, c, 0.0);
      *e_el = Eigen::Vector3d(-sin_el[b] * c, -sin_el[b] * s, cos_el[b]);
    }
    return Eigen::Vector3d(cos_el[b] * c, cos_el[b] * s, sin_el[b]);
  };
  const float min_r = static_cast<float>(options_.min_range_m);
  const float max_r = static_cast<float>(options_.max_range_m);

  auto cast = [&](int f_begin, int f_end) {
    std::vector<Eigen::Vector3f> origins(nb), dirs(nb);
    std::vector<uint64_t> keys(nb);
    std::vector<RayHit> hits(nb);
    for (int f = f_begin; f < f_end; ++f) {
      const double t = t_start_s + f * firing_dt;
      const Eigen::Isometry3d T_world_lidar = trajectory.Pose(t) * T_body_lidar;
      const double az = M_PI - 2.0 * M_PI * f / nf;
      const double ca = std::cos(az), sa = std::sin(az);
      const Eigen::Vector3f o = T_world_lidar.translation().cast<float>();
      const Eigen::Matrix3f R = T_world_lidar.linear().cast<float>();
      for (int b = 0; b < nb; ++b) {
        origins[b] = o;
        dirs[b] = R * beam_dir(b, ca, sa, nullptr, nullptr).cast<float>();
        keys[b] = ray_key(b, f) ^ 0x7E6E7A71ull << 8;
      }
      world.IntersectScattering(origins.data(), dirs.data(), keys.data(), nb, min_r, max_r,
                                hits.data());
      for (int b = 0; b < nb; ++b) {
        const RayHit& h = hits[b];
        if (h.range_m < 0.f) continue;
        const float cos_inc = std::abs(h.normal_world.dot(dirs[b]));
        if (cos_inc < options_.min_cos_incidence) continue;
        const size_t idx = static_cast<size_t>(b) * nf + f;
        hit_range[idx] = h.range_m;
        hit_cos[idx] = cos_inc;
        hit_albedo[idx] = h.albedo;
        hit_volume[idx] = h.volume_return ? 1 : 0;
        p_world[idx] = o + dirs[b] * h.range_m;
        n_world[idx] = h.normal_world;
        surf[idx] = h.surface;
      }
    }
  };

  const bool divergence = options_.beam_divergence_rad > 0.0;
  auto finish = [&](int f_begin, int f_end) {
    std::vector<Eigen::Vector3f> origins(6), dirs(6);
    std::vector<uint64_t> keys(6);
    std::vector<RayHit> hits(6);
    int pose_f = -1;
    Eigen::Isometry3d T_world_lidar = Eigen::Isometry3d::Identity();
    for (int f = f_begin; f < f_end; ++f) {
      for (int b = 0; b < nb; ++b) {
        const size_t idx = static_cast<size_t>(b) * nf + f;
        double r_true = hit_range[idx];
        if (r_true < 0.0) continue;
        double shaded = hit_albedo[idx] * (0.3 + 0.7 * hit_cos[idx]);
        // A return from inside a scattering volume is already one draw of its depth distribution:
        // its footprint is not resampled (edges of the volume are, from the pixels beside it).
        if (divergence && hit_volume[idx] == 0 &&
            IsDepthEdge(hit_range, p_world, n_world, nb, nf, b, f,
                        options_.mixed_pixel_edge_threshold_m)) {
          // Sample the footprint: centre (pass 1) and a hexagon at 2/3 of its radius.
          if (pose_f != f) {
            T_world_lidar = trajectory.Pose(t_start_s + f * firing_dt) * T_body_lidar;
            pose_f = f;
          }
          const double az = M_PI - 2.0 * M_PI * f / nf;
          Eigen::Vector3d e_az, e_el;
          const Eigen::Vector3d d = beam_dir(b, std::cos(az), std::sin(az), &e_az, &e_el);
          const double rho = options_.beam_divergence_rad / 3.0;  // (2/3) * (divergence / 2)
          const Eigen::Vector3f o = T_world_lidar.translation().cast<float>();
          for (int k = 0; k < 6; ++k) {
            const double phi = k * M_PI / 3.0;
            const Eigen::Vector3d dk =
                (d + rho * (std::cos(phi) * e_az + std::sin(phi) * e_el)).normalized();
            origins[k] = o;
            dirs[k] = (T_world_lidar.linear() * dk).cast<float>();
            keys[k] = ray_key(b, f) ^ (0xF00Dull + k) << 48;
          }
          world.IntersectScattering(origins.data(), dirs.data(), keys.data(), 6, min_r, max_r,
                                    hits.data());
          Echo echoes[7];
          int n = 0;
          echoes[n++] = {r_true, hit_albedo[idx], hit_cos[idx], surf[idx]};
          for (int k = 0; k < 6; ++k) {
            const RayHit& h = hits[k];
            if (h.range_m < 0.f) continue;
            const float c = std::abs(h.normal_world.dot(dirs[k]));
            if (c < options_.min_cos_incidence) continue;
            echoes[n++] = {h.range_m, h.albedo, c, h.surface};
          }
          SurfaceClass cls = surf[idx];
          MergeEchoes(echoes, n, 7, options_.mixed_pixel_max_separation_m, &r_true, &shaded, &cls);
          surf[idx] = cls;
        }
        const LaserError& le = laser[b];
        const uint64_t key = ray_key(b, f);
        const double r = (1.0 + le.range_scale) * r_true + le.range_offset_m +
                         options_.range_noise_sigma_m * HashNormal(key);
        if (r < options_.min_range_m || r > options_.max_range_m) continue;
        const double p_drop = options_.dropout_base + options_.dropout_far *
                                                          (1.0 - hit_albedo[idx]) *
                                                          std::clamp((r - 30.0) / 90.0, 0.0, 1.0);
        if (p_drop > 0.0 && HashUniform(key ^ 0xD20Bull << 24) < p_drop) continue;
        range[idx] = static_cast<float>(r);
        const double rf =
            shaded + options_.reflectance_noise_sigma * HashNormal(key ^ 0x5EEDULL << 20);
        refl[idx] = static_cast<float>(std::clamp(rf, 0.0, 1.0));
      }
    }
  };
  const int threads = std::max(1, std::min(num_threads, 16));
  for (const auto& stage :
       {std::function<void(int, int)>(cast), std::function<void(int, int)>(finish)}) {
    if (threads == 1) {
      stage(0, nf);
    } else {
      std::vector<std::thread> pool;
      for (int k = 0; k < threads; ++k)
        pool.emplace_back(stage, nf * k / threads, nf * (k + 1) / threads);
      for (auto& th : pool) th.join();
    }
  }

  Output out;
  out.scan.index = scan_index;
  out.scan.stamp_start = trajectory.ToTimestamp(t_start_s);
  out.scan.stamp_end = trajectory.ToTimestamp(t_start_s + LastFiringOffsetSeconds());
  out.scan.stamp_trigger = trajectory.ToTimestamp(t_start_s + 0.5 * PeriodSeconds());
  size_t count = 0;
  for (float r : range) count += r > 0.f ? 1 : 0;
  out.scan.cloud.reserve(count);
  out.p_world_exact.reserve(count);
  out.surfaces.reserve(count);
  out.beams.reserve(count);
  for (int b = 0; b < nb; ++b) {
    for (int f = 0; f < nf; ++f) {
      const size_t idx = static_cast<size_t>(b) * nf + f;
      if (range[idx] <= 0.f) continue;
      const double az = M_PI - 2.0 * M_PI * f / nf;
      const Eigen::Vector3f p(static_cast<float>(range[idx] * cos_el_w[b] * std::cos(az)),
                              static_cast<float>(range[idx] * cos_el_w[b] * std::sin(az)),
                              static_cast<float>(range[idx] * sin_el_w[b]));
      out.scan.cloud.Add(p, refl[idx], static_cast<float>(f * firing_dt));
      out.p_world_exact.push_back(p_world[idx]);
      out.surfaces.push_back(surf[idx]);
      out.beams.push_back(static_cast<uint8_t>(b));
    }
  }
  return out;
}

}  // namespace slam_mms::sim
