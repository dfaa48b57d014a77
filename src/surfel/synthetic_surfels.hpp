#pragma once
// Synthetic surfel scenes for tests and benchmarks (not part of the public API): a street with a
// ground plane, two facades and boxes, sampled uniformly by area, radii as SuMa gives them for a
// sensor at the origin (1.41 * range * pixel size / cos(incidence), clamped to [0.05, 1] m).
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "slam_mms/surfel/surfel.hpp"

namespace slam_mms::internal {

inline float SumaRadius(const Eigen::Vector3f& p_sensor, const Eigen::Vector3f& n,
                        float pixel_size = 0.0038f) {
  const float d = p_sensor.norm();
  const float c = std::clamp(std::fabs(n.dot(p_sensor / d)), 0.5f, 1.0f);
  return std::clamp(1.41f * d * pixel_size / c, 0.05f, 1.0f);
}

/// `n` surfels of a street around the origin (sensor 1.73 m above the ground), seeded.
inline std::vector<Surfel> MakeStreetSurfels(size_t n, uint32_t seed, float half_length_m = 60.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  std::vector<Surfel> out;
  out.reserve(n);
  const float L = half_length_m;
  const float ground_area = 2 * L * 16.0f;
  const float facade_area = 2 * (2 * L * 12.0f);
  const float box_area = 40 * (4 * 4.0f * 3.0f);
  const float total = ground_area + facade_area + box_area;
  std::vector<Eigen::Vector3f> boxes;
  for (int b = 0; b < 40; ++b)
    boxes.emplace_back(-L + 2 * L * uni(rng), -6.0f + 12.0f * uni(rng), 0);
  for (size_t i = 0; i < n; ++i) {
    Surfel s;
    const float pick = uni(rng) * total;
    if (pick < ground_area) {
      s.position = {-L + 2 * L * uni(rng), -8.0f + 16.0f * uni(rng), -1.73f};
      s.normal = Eigen::Vector3f::UnitZ();
    } else if (pick < ground_area + facade_area) {
      const float side = uni(rng) < 0.5f ? -1.0f : 1.0f;
      s.position = {-L + 2 * L * uni(rng), side * 8.0f, -1.73f + 12.0f * uni(rng)};
      s.normal = Eigen::Vector3f(0, -side, 0);
    } else {
      const Eigen::Vector3f& c = boxes[static_cast<size_t>(uni(rng) * 39.999f)];
      const int face = static_cast<int>(uni(rng) * 3.999f);
      const float a = -1.0f + 2.0f * uni(rng);
      const float z = -1.73f + 3.0f * uni(rng);
      const Eigen::Vector3f offs[4] = {{1, a, 0}, {-1, a, 0}, {a, 1, 0}, {a, -1, 0}};
      s.normal =
          Eigen::Vector3f(offs[face].x() == 1 || offs[face].x() == -1 ? offs[face].x() : 0,
                          offs[face].y() == 1 || offs[face].y() == -1 ? offs[face].y() : 0, 0);
      s.position = c + offs[face];
      s.position.z() = z;
    }
    // A small random tilt so that not every normal is axis-aligned.
    s.normal =
        (s.normal + 0.05f * Eigen::Vector3f(uni(rng) - 0.5f, uni(rng) - 0.5f, uni(rng) - 0.5f))
            .normalized();
    s.radius = SumaRadius(s.position, s.normal);
    s.confidence = 1.0f;
    out.push_back(s);
  }
  return out;
}

}  // namespace slam_mms::internal
