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
// Optional realism models (off by default; docs/simulator.md "Realism models"):
// - Ground roughness (Options::*_roughness_rms_m): ground hits are displaced along the surface
//   normal by a fixed, seeded height texture (value noise, 0.1-0.4 m wavelengths) of the stated
//   RMS per class, so every scan sees the same rough surface. Applied inside Intersect.
// - Volumetric vegetation (Options::volumetric_vegetation): tree crowns become closed, lumpy hulls
//   and hedges appear along yards and open lots; a hull is a scattering volume (a triangle with
//   TriangleMesh::mean_free_path_m > 0), and IntersectScattering returns points inside it at an
//   exponentially distributed penetration depth (Beer-Lambert), or lets the ray pass through.
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
  /// Empty (all solid) or one per triangle: > 0 marks a face of a closed, outward-wound hull of a
  /// scattering volume (vegetation) with this mean free path [m]; 0 = a solid surface.
  std::vector<float> mean_free_path_m;

  void AddTriangle(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c,
                   SurfaceClass cls, float albedo);
  /// An oriented box: centre, unit axes (columns of R), half sizes; 12 triangles.
  void AddBox(const Eigen::Vector3f& center, const Eigen::Matrix3f& R,
              const Eigen::Vector3f& half_size, SurfaceClass cls, float albedo);
  /// A vertical prism (cylinder approximation) standing on `base`.
  void AddCylinder(const Eigen::Vector3f& base, float radius, float height, int sides,
                   SurfaceClass cls, float albedo);
  void Append(const TriangleMesh& other);
  /// Sets the mean free path of triangles [first, end) (filling earlier ones with 0).
  void MarkVolume(size_t first_triangle, float mean_free_path_m);
};

/// What a ray hit.
struct RayHit {
  float range_m = -1.0f;  ///< Distance along the (unit) ray; < 0: no hit within max range.
  Eigen::Vector3f normal_world =
      Eigen::Vector3f::Zero();  ///< Unit geometric normal, facing the ray.
  SurfaceClass surface = SurfaceClass::kOther;
  float albedo = 0.0f;  ///< Reflectance of the surface at the hit (lane markings included).
  /// > 0: the hit is on the hull of a scattering volume with this mean free path [m] (Intersect
  /// only; IntersectScattering resolves volumes into returns inside them).
  float mean_free_path_m = 0.0f;
  bool entering = false;       ///< The ray crosses the hull from outside to inside.
  bool volume_return = false;  ///< IntersectScattering: a return from inside a volume.
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
    /// Ground roughness, RMS height of the texture [m] (0 = off): road and lane markings;
    /// sidewalks and curb faces; terrain (verges, lots).
    double road_roughness_rms_m = 0.0;
    double sidewalk_roughness_rms_m = 0.0;
    double terrain_roughness_rms_m = 0.0;
    /// Tree crowns as scattering volumes (instead of leaf triangles) and hedges.
    bool volumetric_vegetation = false;
    double foliage_mean_free_path_m = 1.0;  ///< Tree crowns [m].
    double hedge_mean_free_path_m = 0.3;    ///< Hedges [m].
    double hedge_probability = 0.5;  ///< Per fenced yard or open lot, with volumetric_vegetation.

    /// docs/simulator.md's values: roughness 5 mm road, 8 mm sidewalk, 3 cm terrain.
    void EnableGroundRoughness();

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
    int num_hedges = 0;  ///< With Options::volumetric_vegetation.
    double path_length_m = 0.0;
  };

  /// A driven span of a trajectory, one of the paths of Build(paths, options). The trajectory is
  /// borrowed for the call only.
  struct PathSpan {
    const ReferenceTrajectory* trajectory = nullptr;
    double t_begin_s = 0.0;  ///< Clamped to the trajectory like Build's.
    double t_end_s = 0.0;
  };

  /// Generates the city along `trajectory` (its positions sampled every 0.5 m of travel) between
  /// trajectory seconds `t_begin_s` and `t_end_s` (clamped to the trajectory; streets continue 80 m
  /// beyond both ends).
  [[nodiscard]] static StatusOr<CityWorld> Build(const ReferenceTrajectory& trajectory,
                                                 const Options& options, double t_begin_s,
                                                 double t_end_s);
  [[nodiscard]] static StatusOr<CityWorld> Build(const ReferenceTrajectory& trajectory,
                                                 const Options& options);
  /// Generates one city along several driven paths (e.g. the route variants of a scenario, so that
  /// several drives see the same streets): the union of the paths' streets, in the order given.
  /// Paths are never joined to each other (no street between one path's end and the next one's
  /// start); a street driven by several paths, or twice, in either direction (within 2.5 m,
  /// headings within about 37 deg of parallel or antiparallel), exists once, with the first pass's
  /// width and objects. The world depends on the paths and `options` only, so every drive along one
  /// of the paths sees the same world. With one path it may differ from Build(trajectory, ...)
  /// where that path drives a street twice in opposite directions (Build merges same-direction
  /// revisits only). InvalidArgument where `paths` is empty, a trajectory is null or a span is
  /// empty.
  [[nodiscard]] static StatusOr<CityWorld> Build(const std::vector<PathSpan>& paths,
                                                 const Options& options);
  /// A world of the given triangles (tests, custom scenes). With `options`, its seed and ground
  /// roughness apply (to triangles of the ground classes road, marking, curb, sidewalk, terrain).
  [[nodiscard]] static StatusOr<CityWorld> FromMesh(TriangleMesh mesh);
  [[nodiscard]] static StatusOr<CityWorld> FromMesh(TriangleMesh mesh, const Options& options);

  CityWorld(CityWorld&&) noexcept;
  CityWorld& operator=(CityWorld&&) noexcept;
  CityWorld(const CityWorld&) = delete;
  CityWorld& operator=(const CityWorld&) = delete;
  ~CityWorld();

  /// Casts `n` rays (unit directions) from `origins`, hits beyond `max_range_m` or closer than
  /// `min_range_m` are misses. Uses Embree ray packets of 16.
  void Intersect(const Eigen::Vector3f* origins, const Eigen::Vector3f* directions, size_t n,
                 float min_range_m, float max_range_m, RayHit* hits) const;

  /// Intersect, then every ray entering a scattering volume penetrates it by a depth drawn from
  /// an exponential distribution of the volume's mean free path (uniforms from `keys[i]`, one per
  /// ray, counter-based): a return inside (normal in a random direction, volume_return = true) or
  /// on through to whatever lies beyond. Solid hits inside a volume (a trunk) stop the ray.
  void IntersectScattering(const Eigen::Vector3f* origins, const Eigen::Vector3f* directions,
                           const uint64_t* keys, size_t n, float min_range_m, float max_range_m,
                           RayHit* hits) const;

  /// The ground-roughness height texture of class `cls` at (x, y) [m] (0 where off or not ground).
  double RoughnessHeight(double x, double y, SurfaceClass cls) const;

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
