#pragma once
// CityWorld: the simulator's procedural urban scene, generated along a trajectory and deterministic
// by seed, held as Embree 3 triangle geometry for ray casting.
//
// Streets are the swept band around the driven path (so every driven street, its intersections and
// a revisited street exist once): asphalt with lane markings, curbs (a vertical step), sidewalks,
// then lots with building blocks of varied height and depth (gaps, alleys, setbacks, stepped upper
// floors, floor ledges), fenced yards, open lots; along the curbs street lamps, sign posts, trees
// (porous crowns of leaf triangles) and parked cars; the ground follows the road height of the
// nearest path point. Materials carry a reflectance (albedo) that the LiDAR model shades.
//
// Ownership: move-only; owns its Embree device and scene. Thread safety: after Build/FromMesh, all
// const methods (Intersect in particular) may be called concurrently.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/sim/reference_trajectory.hpp"

namespace slam_mms::sim {

/// Surface classes of the scene (also the PLY/label output of the simulator).
enum class SurfaceClass : uint8_t {
  kRoad = 0,
  kMarking = 1,
  kCurb = 2,
  kSidewalk = 3,
  kTerrain = 4,
  kBuilding = 5,
  kPole = 6,
  kTrunk = 7,
  kFoliage = 8,
  kCar = 9,
  kFence = 10,
  kOther = 11,
};
const char* SurfaceClassName(SurfaceClass c);

/// A triangle soup with per-triangle class and albedo (reflectance in [0, 1]).
struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3i> triangles;
  std::vector<SurfaceClass> classes;  ///< One per triangle.
  std::vector<float> albedo;          ///< One per triangle.

  void AddTriangle(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c,
                   SurfaceClass cls, float albedo);
  /// An oriented box: centre, unit axes (columns of R), half sizes; 12 triangles.
  void AddBox(const Eigen::Vector3f& center, const Eigen::Matrix3f& R,
              const Eigen::Vector3f& half_size, SurfaceClass cls, float albedo);
  /// A vertical prism (cylinder approximation) standing on `base`.
  void AddCylinder(const Eigen::Vector3f& base, float radius, float height, int sides,
                   SurfaceClass cls, float albedo);
  void Append(const TriangleMesh& other);
};

/// What a ray hit.
struct RayHit {
  float range_m = -1.0f;  ///< Distance along the (unit) ray; < 0: no hit within max range.
  Eigen::Vector3f normal_world =
      Eigen::Vector3f::Zero();  ///< Unit geometric normal, facing the ray.
  SurfaceClass surface = SurfaceClass::kOther;
  float albedo = 0.0f;  ///< Reflectance of the surface at the hit (lane markings included).
};

class CityWorld {
 public:
  struct Options {
    uint64_t seed = 1;
    double corridor_m = 70.0;    ///< Ground is generated up to this far from the path [m].
    double ground_cell_m = 0.5;  ///< Ground grid spacing [m].
    double body_height_above_road_m = 0.93;  ///< IMU above the road (KITTI: about 0.93 m).
    double road_half_width_min_m = 4.5;      ///< Per street, drawn in [min, max] [m].
    double road_half_width_max_m = 7.0;
    double sidewalk_width_min_m = 2.0;  ///< Per street [m].
    double sidewalk_width_max_m = 4.0;
    double curb_height_m = 0.14;
    double building_height_min_m = 6.0;
    double building_height_max_m = 26.0;
    double building_probability = 0.68;  ///< Per lot: building (else gap, fenced yard or open lot).
    double pole_spacing_m = 30.0;        ///< Mean spacing of lamps and sign posts per side [m].
    double tree_probability = 0.5;       ///< Per 60 m stretch of sidewalk: a row of trees.
    double parked_car_probability = 0.45;  ///< Per 40 m stretch of curb: a row of parked cars.

    [[nodiscard]] Status Validate() const;
  };

  /// Counts of what Build generated.
  struct Stats {
    size_t num_triangles = 0;
    size_t num_ground_triangles = 0;
    int num_buildings = 0;
    int num_trees = 0;
    int num_poles = 0;
    int num_cars = 0;
    int num_fences = 0;
    double path_length_m = 0.0;
  };

  /// Generates the city along `trajectory` (its positions sampled every 0.5 m of travel) between
  /// trajectory seconds `t_begin_s` and `t_end_s` (clamped to the trajectory; streets continue 80 m
  /// beyond both ends).
  [[nodiscard]] static StatusOr<CityWorld> Build(const ReferenceTrajectory& trajectory,
                                                 const Options& options, double t_begin_s,
                                                 double t_end_s);
  [[nodiscard]] static StatusOr<CityWorld> Build(const ReferenceTrajectory& trajectory,
                                                 const Options& options);
  /// A world of the given triangles (tests, custom scenes).
  [[nodiscard]] static StatusOr<CityWorld> FromMesh(TriangleMesh mesh);

  CityWorld(CityWorld&&) noexcept;
  CityWorld& operator=(CityWorld&&) noexcept;
  CityWorld(const CityWorld&) = delete;
  CityWorld& operator=(const CityWorld&) = delete;
  ~CityWorld();

  /// Casts `n` rays (unit directions) from `origins`, hits beyond `max_range_m` or closer than
  /// `min_range_m` are misses. Uses Embree ray packets of 16.
  void Intersect(const Eigen::Vector3f* origins, const Eigen::Vector3f* directions, size_t n,
                 float min_range_m, float max_range_m, RayHit* hits) const;

  /// Fraction of `num_rays` rays from `p_world` into the upper hemisphere between `min_elevation`
  /// and 90 deg that hit the scene within 300 m: the sky blockage seen by a GNSS antenna.
  double SkyBlockage(const Eigen::Vector3d& p_world, int num_rays = 48,
                     double min_elevation_deg = 15.0) const;

  /// Road surface height at the path point nearest to (x, y) (the ground model) [m].
  double GroundHeight(double x, double y) const;

  const TriangleMesh& mesh() const;
  const Stats& stats() const;

  struct Impl;  ///< Internal (defined in src/sim); not part of the API.

 private:
  explicit CityWorld(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms::sim
