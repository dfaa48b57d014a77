// Hdl64Lidar: per-firing ray casting along the true trajectory.
#include "slam_mms/sim/hdl64_lidar.hpp"

#include <algorithm>
#include <cmath>
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

}  // namespace

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
  return OkStatus();
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
  std::vector<double> cos_el(nb), sin_el(nb), cos_el_w(nb), sin_el_w(nb);
  for (int b = 0; b < nb; ++b) {
    cos_el[b] = std::cos(elevations_deg_[b] * deg);
    sin_el[b] = std::sin(elevations_deg_[b] * deg);
    const double written = (elevations_deg_[b] - options_.elevation_bias_deg) * deg;
    cos_el_w[b] = std::cos(written);
    sin_el_w[b] = std::sin(written);
  }
  // Per (beam, firing) results; range < 0 = no return.
  const size_t total = static_cast<size_t>(nb) * nf;
  std::vector<float> range(total, -1.f), refl(total, 0.f);
  std::vector<Eigen::Vector3f> p_world(total);
  std::vector<SurfaceClass> surf(total, SurfaceClass::kOther);
  const uint64_t scan_key = MixSeed(seed, 0x11DA5 + static_cast<uint64_t>(scan_index));

  auto work = [&](int f_begin, int f_end) {
    std::vector<Eigen::Vector3f> origins(nb), dirs(nb);
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
        dirs[b] =
            R * Eigen::Vector3f(static_cast<float>(cos_el[b] * ca),
                                static_cast<float>(cos_el[b] * sa), static_cast<float>(sin_el[b]));
      }
      world.Intersect(origins.data(), dirs.data(), nb, static_cast<float>(options_.min_range_m),
                      static_cast<float>(options_.max_range_m), hits.data());
      for (int b = 0; b < nb; ++b) {
        const RayHit& h = hits[b];
        if (h.range_m < 0.f) continue;
        const float cos_inc = std::abs(h.normal_world.dot(dirs[b]));
        if (cos_inc < options_.min_cos_incidence) continue;
        const uint64_t key = scan_key ^ (static_cast<uint64_t>(b) << 40) ^ static_cast<uint64_t>(f);
        const double r = h.range_m + options_.range_noise_sigma_m * HashNormal(key);
        if (r < options_.min_range_m || r > options_.max_range_m) continue;
        const double p_drop = options_.dropout_base + options_.dropout_far * (1.0 - h.albedo) *
                                                          std::clamp((r - 30.0) / 90.0, 0.0, 1.0);
        if (p_drop > 0.0 && HashUniform(key ^ 0xD20Bull << 24) < p_drop) continue;
        const size_t idx = static_cast<size_t>(b) * nf + f;
        range[idx] = static_cast<float>(r);
        const double rf = h.albedo * (0.3 + 0.7 * cos_inc) +
                          options_.reflectance_noise_sigma * HashNormal(key ^ 0x5EEDULL << 20);
        refl[idx] = static_cast<float>(std::clamp(rf, 0.0, 1.0));
        p_world[idx] = o + dirs[b] * h.range_m;
        surf[idx] = h.surface;
      }
    }
  };
  const int threads = std::max(1, std::min(num_threads, 16));
  if (threads == 1) {
    work(0, nf);
  } else {
    std::vector<std::thread> pool;
    for (int k = 0; k < threads; ++k)
      pool.emplace_back(work, nf * k / threads, nf * (k + 1) / threads);
    for (auto& th : pool) th.join();
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
