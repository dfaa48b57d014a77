#pragma once
// Test-only synthetic scenes made of rectangles, ray-cast like a spinning LiDAR: an urban street
// (ground, facades, boxes, a tilted plane) that constrains all six DOF, and a long corridor
// (tunnel) that leaves translation along its axis unobservable.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/surfel/range_projection.hpp"
#include "slam_mms/surfel/vertex_normal_map.hpp"

namespace slam_mms::testing {

struct Rect {
  Eigen::Vector3d c, a, b;  // centre, unit in-plane axes
  double ha, hb;            // half extents along a, b
  Eigen::Vector3d n() const { return a.cross(b).normalized(); }
};

struct Scene {
  std::vector<Rect> rects;

  void AddRect(const Eigen::Vector3d& c, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
               double ha, double hb) {
    rects.push_back({c, a.normalized(), b.normalized(), ha, hb});
  }
  /// Axis-aligned box (5 faces: no bottom) from min corner to max corner, rotated by yaw about z
  /// around its centre.
  void AddBox(const Eigen::Vector3d& center, const Eigen::Vector3d& half, double yaw) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d ex = R.col(0), ey = R.col(1), ez = R.col(2);
    AddRect(center + half.x() * ex, ey, ez, half.y(), half.z());
    AddRect(center - half.x() * ex, ey, ez, half.y(), half.z());
    AddRect(center + half.y() * ey, ex, ez, half.x(), half.z());
    AddRect(center - half.y() * ey, ex, ez, half.x(), half.z());
    AddRect(center + half.z() * ez, ex, ey, half.x(), half.y());
  }

  /// Nearest hit along o + t d (d unit), t in (0, max_t]; returns t or +inf, normal of the hit.
  double Cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_t,
              Eigen::Vector3d* normal) const {
    double best = std::numeric_limits<double>::infinity();
    for (const Rect& r : rects) {
      const Eigen::Vector3d n = r.n();
      const double den = n.dot(d);
      if (std::abs(den) < 1e-9) continue;
      const double t = n.dot(r.c - o) / den;
      if (t <= 1e-6 || t > max_t || t >= best) continue;
      const Eigen::Vector3d x = o + t * d - r.c;
      if (std::abs(x.dot(r.a)) > r.ha || std::abs(x.dot(r.b)) > r.hb) continue;
      best = t;
      *normal = den < 0.0 ? n : Eigen::Vector3d(-n);  // towards the ray origin
    }
    return best;
  }
};

/// A street 1.7 m below the sensor origin of the world frame, running along x.
inline Scene MakeStreetScene() {
  Scene s;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY();
  s.AddRect({0, 0, -1.7}, X, Y, 80, 80);  // ground
  // Facades with gaps (so x is constrained by the side faces of the houses too).
  for (int i = -4; i <= 4; ++i) {
    s.AddBox({i * 16.0, 14.0, 4.0}, {6.0, 4.0, 5.7}, 0.0);
    s.AddBox({i * 16.0 + 5.0, -15.0, 3.0}, {5.0, 4.0, 4.7}, 0.0);
  }
  // Boxes on the road side: cars, poles, a kiosk at an angle.
  s.AddBox({8.0, 4.0, -1.0}, {2.2, 0.9, 0.7}, 0.0);
  s.AddBox({-12.0, -5.0, -1.0}, {2.2, 0.9, 0.7}, 0.3);
  s.AddBox({20.0, -4.0, 0.0}, {1.5, 1.5, 1.7}, 0.6);
  s.AddBox({5.0, -6.5, 1.0}, {0.15, 0.15, 2.7}, 0.0);
  s.AddBox({-6.0, 7.0, 1.0}, {0.15, 0.15, 2.7}, 0.0);
  // A tilted plane (a ramp / roof) ahead.
  s.AddRect({35.0, 2.0, 1.0}, Eigen::Vector3d(0.3, 0.0, 1.0), Y, 6.0, 8.0);
  return s;
}

/// A straight corridor along x: floor, ceiling and two walls, far longer than the sensor range.
inline Scene MakeTunnelScene() {
  Scene s;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  s.AddRect({0, 0, -1.7}, X, Y, 400, 3.0);
  s.AddRect({0, 0, 2.8}, X, Y, 400, 3.0);
  s.AddRect({0, 3.0, 0.55}, X, Z, 400, 2.25);
  s.AddRect({0, -3.0, 0.55}, X, Z, 400, 2.25);
  return s;
}

/// A LiDAR scan of `scene` from T_world_sensor, one ray per pixel with the direction jittered
/// uniformly inside the pixel and Gaussian range noise; points in the sensor frame.
inline PointCloud SimulateScan(const Scene& scene, const RangeProjection& proj,
                               const Eigen::Isometry3d& T_world_sensor, double range_noise_m,
                               uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(0.02f, 0.98f);
  std::normal_distribution<double> noise(0.0, range_noise_m);
  PointCloud cloud;
  cloud.reserve(static_cast<size_t>(proj.rows() * proj.cols()));
  const Eigen::Vector3d o = T_world_sensor.translation();
  const Eigen::Matrix3d R = T_world_sensor.linear();
  const double max_r = proj.options().max_range_m;
  for (int row = 0; row < proj.rows(); ++row) {
    for (int col = 0; col < proj.cols(); ++col) {
      const Eigen::Vector3f d_s = proj.Unproject(static_cast<float>(col) + jitter(rng),
                                                 static_cast<float>(row) + jitter(rng), 1.0f)
                                      .normalized();
      Eigen::Vector3d n;
      const double t = scene.Cast(o, R * d_s.cast<double>(), max_r, &n);
      if (!std::isfinite(t)) continue;
      const double r = t + (range_noise_m > 0.0 ? noise(rng) : 0.0);
      if (r < proj.options().min_range_m) continue;
      cloud.Add((r * d_s.cast<double>()).cast<float>());
    }
  }
  return cloud;
}

/// The exact model image of `scene` seen from T_world_model: one ray through each pixel centre,
/// vertex and (sensor-facing) normal in the model's sensor frame. The stand-in for a rendered map.
inline VertexNormalMap RenderModel(const Scene& scene, const RangeProjection& proj,
                                   const Eigen::Isometry3d& T_world_model) {
  VertexNormalMap m;
  m.Reset(proj.rows(), proj.cols());
  const Eigen::Vector3d o = T_world_model.translation();
  const Eigen::Matrix3d R = T_world_model.linear();
  for (int row = 0; row < proj.rows(); ++row) {
    for (int col = 0; col < proj.cols(); ++col) {
      const Eigen::Vector3d d = proj.RayDirection(row, col).cast<double>();
      Eigen::Vector3d n_world;
      const double t = scene.Cast(o, R * d, proj.options().max_range_m, &n_world);
      if (!std::isfinite(t) || t < proj.options().min_range_m) continue;
      const size_t i = static_cast<size_t>(m.PixelIndex(row, col));
      m.vertex[i] = (t * d).cast<float>();
      m.normal[i] = (R.transpose() * n_world).cast<float>();
      m.range[i] = static_cast<float>(t);
      m.index[i] = static_cast<int32_t>(i);
    }
  }
  return m;
}

}  // namespace slam_mms::testing
