#pragma once
// CityWorld internals shared by city_world.cpp (mesh, Embree, queries) and city_generator.cpp.
#include <embree3/rtcore.h>

#include <vector>

#include "sim/path_index.hpp"
#include "slam_mms/sim/city_world.hpp"

namespace slam_mms::sim {

struct CityWorld::Impl {
  Options options;
  Stats stats;
  TriangleMesh mesh;
  // Ground vertices come first in `mesh`; for them: distance to the path, canonical arc length and
  // the road half width (lane markings are shaded from these).
  size_t num_ground_vertices = 0;
  size_t num_ground_triangles = 0;
  std::vector<float> vertex_d, vertex_s, vertex_w;
  bool has_path = false;
  PathIndex path;

  bool has_volumes = false;  ///< Some triangle has mean_free_path_m > 0.
  /// Roughness lattice values, 3 octaves of kTextureSize^2 (filled in Commit where rough).
  static constexpr int64_t kTextureSize = 256;
  std::vector<float> texture;

  RTCDevice device = nullptr;
  RTCScene scene = nullptr;

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl();

  /// Builds the Embree scene from `mesh`.
  Status Commit();
  /// Albedo at a hit on triangle `prim` with barycentrics (u, v).
  float ShadeAlbedo(unsigned prim, float u, float v, SurfaceClass* cls) const;
  /// Fills `h` for a hit at distance t along (o, d) on triangle `prim` (barycentrics u, v; raw
  /// geometric normal ng): normal facing the ray, class, albedo, volume flags, ground roughness.
  void FinishHit(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t, unsigned prim,
                 float u, float v, Eigen::Vector3f ng, RayHit* h) const;
  /// One ray (rtcIntersect1), finished like Intersect's.
  RayHit IntersectOne(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float tnear,
                      float tfar) const;
  /// Height texture of unit RMS at (x, y) (value noise, 3 octaves, seeded by options.seed).
  double Texture(double x, double y) const;
  /// Ground roughness RMS of class `cls` [m] (0: not a ground class or off).
  double RoughnessRms(SurfaceClass cls) const;
  /// Ground height model at (x, y) without curb snapping.
  double GroundModelHeight(const Eigen::Vector2d& q, double* d_out,
                           const PathSample** street) const;
};

/// Generates the procedural city into `impl` (path, ground, objects) along `spans` (already
/// clamped to their trajectories); does not commit. `either_direction`: a street driven in the
/// opposite direction is a revisit too (CityWorld::Build of several paths).
Status GenerateCity(const std::vector<CityWorld::PathSpan>& spans, bool either_direction,
                    CityWorld::Impl* impl);

}  // namespace slam_mms::sim
