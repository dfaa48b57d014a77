#pragma once
// SurfelMap: the SuMa-style surfel map of the mapping module (paper §5.1.2; Behley & Stachniss
// 2018; see /work/shared/SUMA_DIGEST.md §2-§3 for the original and the defects not copied).
//
// Integrate(scan, T_world_sensor, stamp), one de-skewed scan at its (registered) pose:
//   1. Select the active surfels within active_radius_m of the sensor (voxel-hash index).
//   2. Render them at the pose (the map's SurfelRenderer; CPU by default, SetRenderer for EGL).
//   3. Per scan pixel with vertex and normal: the rendered surfel s there EXPLAINS the measurement
//   if
//      d = |n_s . (v - p_s)| < max_distance_m and |n_v x n_s| < sin(max_angle_deg) (SuMa's gates);
//      an explained pixel creates no new surfel. If instead the measured range lies beyond the
//      rendered range by more than max_distance_m, the ray passed through s: a CONFLICT for s.
//      (SuMa counts any incompatible measurement as a conflict; a surface newly seen in front of a
//      surfel is an occlusion, not evidence against it, so it is not counted here.)
//   4. Per active surfel: project its centre into the scan; if that pixel's measurement is
//   compatible
//      (same gates) the surfel is CONFIRMED (and that pixel counts as explained, as in SuMa):
//      log-odds l += ln(p/(1-p)) - l_prior with p = p_stable * exp(-a^2/sigma_angle^2) *
//      exp(-d^2/sigma_distance^2) clamped to [1-p_stable, 1), radius := min(radius, r_new), and if
//      it is younger than max_update_age_frames its position and normal become the running weighted
//      average with the measurement (weight min(updates+1, max_weight); SuMa's slerp NaN avoided by
//      averaging and renormalising). Otherwise, with a conflict, l += ln(p_unstable / p_stable)
//      (SuMa's log_unstable). l is capped at max_confidence.
//   5. Drop unstable surfels: l < ln((1-p_stable)/p_stable), or l <= confidence_threshold and not
//      confirmed for unstable_age_frames integrations. (SuMa tests l < threshold there, so a new
//      surfel (l = 0) that is never confirmed lives forever; with "<=" one-off noise surfels die
//      after unstable_age_frames, which keeps the active map, and its render time, bounded.)
//   6. Create a surfel for each unexplained pixel with a normal facing the sensor:
//      radius = radius_factor * range * pixel_size / clamp(cos(incidence), min_radius_cos, 1)
//      within [min_radius_m, max_radius_m], pixel_size = max(tan(vfov / 2 rows), tan(pi / cols)); l
//      = 0.
//
// Storage: a slot vector; a surfel's id is its slot and stays valid until the surfel is removed
// (slots of removed surfels are reused by later creations) or Compact() renumbers the map.
// Positions are in the map ("world") frame; TransformSubmap moves one submap's surfels rigidly
// after a pose-graph correction.
//
// Ownership: the map owns its surfels and its default CPU renderer; SetRenderer borrows.
// Thread safety: not thread-safe; const methods may run concurrently with each other. Move-only.

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/surfel/surfel.hpp"
#include "slam_mms/surfel/surfel_renderer.hpp"
#include "slam_mms/surfel/vertex_normal_map.hpp"

namespace slam_mms {

struct SurfelMapOptions {
  /// Image geometry of the scans passed to Integrate and of the association render.
  SurfelRendererOptions renderer;
  // Association (SuMa map-max-distance / map-max-angle).
  double max_distance_m = 0.2;  ///< Point-to-plane gate [m].
  double max_angle_deg = 45.0;  ///< Normal gate [deg], compared as |n1 x n2| < sin(angle).
  // Radius of new surfels (SuMa §2).
  double radius_factor = 1.41;
  double min_radius_m = 0.05;
  double max_radius_m = 1.0;
  /// The incidence cosine in the radius formula is clamped to [min_radius_cos, 1] (SuMa: 0.5).
  double min_radius_cos = 0.5;
  double min_creation_cos = 0.01;  ///< New surfel only if n . (-v/|v|) > this (SuMa 0.01).
  // Stability log-odds (SuMa p_stable 0.6, prior 0.5, sigma 1 / 1, threshold 0, age 3, cap 20).
  double p_stable = 0.6;
  double sigma_angle = 1.0;     ///< Of a = |n_v x n_s| (a sine, as SuMa).
  double sigma_distance = 1.0;  ///< Of d [m].
  double confidence_threshold = 0.0;
  int unstable_age_frames = 3;
  double max_confidence = 20.0;
  // Geometry refinement (SuMa averages only while younger than 100 frames, weight cap 20).
  int max_update_age_frames = 100;
  int max_weight = 20;
  // Active map: what Integrate and RenderModel consider.
  double active_radius_m = 80.0;   ///< Surfels within this distance of the sensor [m].
  double index_cell_size_m = 8.0;  ///< Voxel-hash cell edge [m].
  /// Integrate associates and fuses only with surfels of the current submap (SetSubmapId), so each
  /// submap is a self-contained local map as in the paper (§5.1); surfels of other submaps are
  /// neither confirmed nor removed by it. SelectActive / RenderModel still see every submap.
  /// Inside a Localizer it is Level1Options::per_submap_surfels, and Level1Options::surfels
  /// must leave it false (Validate says so): one field decides.
  bool integrate_current_submap_only = false;

  [[nodiscard]] Status Validate() const;
};

/// What one Integrate did.
struct SurfelIntegrationStats {
  int num_active = 0;      ///< Surfels considered (near the pose).
  int num_explained = 0;   ///< Scan pixels explained by the rendered model.
  int num_confirmed = 0;   ///< Surfels confirmed by a compatible measurement.
  int num_conflicts = 0;   ///< Surfels seen through (free-space violation).
  int num_removed = 0;     ///< Unstable surfels dropped.
  int num_created = 0;     ///< New surfels.
  size_t num_surfels = 0;  ///< Map size afterwards.
};

class SurfelMap {
 public:
  /// Default options (HDL-64 64 x 2048 images, SuMa's defaults).
  SurfelMap();
  /// InvalidArgument when options.Validate() fails or num_threads (the calling thread included;
  /// the association, update and CPU-render loops) is outside [1, 64].
  static StatusOr<SurfelMap> Create(const SurfelMapOptions& options, int num_threads = 2);
  ~SurfelMap();
  SurfelMap(SurfelMap&&) noexcept;
  SurfelMap& operator=(SurfelMap&&) noexcept;
  SurfelMap(const SurfelMap&) = delete;
  SurfelMap& operator=(const SurfelMap&) = delete;

  const SurfelMapOptions& options() const;

  /// Uses `renderer` (borrowed; must outlive its use; nullptr restores the built-in CPU renderer)
  /// for the association render. Its image size and FOV must equal options().renderer.projection.
  [[nodiscard]] Status SetRenderer(SurfelRenderer* renderer);
  /// The renderer Integrate and RenderModel use.
  SurfelRenderer& renderer();

  /// Submap id given to surfels created from now on (default 0).
  void SetSubmapId(int32_t submap_id);
  int32_t submap_id() const;

  /// Fuses one scan (vertex/normal maps in the sensor frame, from RangeProjection with the same
  /// options) taken at T_world_sensor. InvalidArgument for a size mismatch or a non-finite pose.
  StatusOr<SurfelIntegrationStats> Integrate(const VertexNormalMap& scan,
                                             const Eigen::Isometry3d& T_world_sensor,
                                             Timestamp stamp);

  /// Ids of the live surfels within radius_m of center_world with confidence > min_confidence
  /// (replaces *ids; reuses its capacity). The order is the spatial index's (cell by cell), the
  /// same for the same map history, not sorted.
  void SelectActive(const Eigen::Vector3d& center_world, double radius_m, float min_confidence,
                    std::vector<uint32_t>* ids) const;
  /// The same ids, the candidates filtered by the map's threads (Create's num_threads); not to
  /// be called concurrently with anything else on this map.
  void SelectActive(const Eigen::Vector3d& center_world, double radius_m, float min_confidence,
                    std::vector<uint32_t>* ids);
  /// Renders the surfels within active_radius_m of the sensor with confidence > min_confidence at
  /// T_world_sensor (the model image for projective ICP). SuMa renders l > 0 once warmed up.
  [[nodiscard]] Status RenderModel(const Eigen::Isometry3d& T_world_sensor, float min_confidence,
                                   VertexNormalMap* out);

  /// All slots; only those with IsAlive(id) are surfels. Ids index this vector.
  const std::vector<Surfel>& surfels() const;
  bool IsAlive(uint32_t id) const;
  /// Number of live surfels.
  size_t size() const;
  /// Copies of the live surfels (for export).
  std::vector<Surfel> LiveSurfels() const;
  /// Integrations so far.
  int32_t frame_count() const;
  /// Heap bytes held: surfel slots, flags, spatial index and scratch buffers.
  size_t MemoryBytes() const;

  /// Removes the listed surfels (ids as in RayHit/VertexNormalMap::index; dead or unknown ids are
  /// ignored), e.g. those a moving object was seen through. Returns how many were removed.
  size_t RemoveSurfels(const std::vector<uint32_t>& ids);

  /// Moves every surfel of `submap_id` by T_new_old (positions and normals); returns how many.
  size_t TransformSubmap(int32_t submap_id, const Eigen::Isometry3d& T_new_old);

  // ---- bounding memory on long drives -----------------------------------------------------------
  // A drive's map grows with its length; the pipeline keeps only the submaps it still registers
  // against. Removing surfels frees their slots (reused by later creations, so the slot vector
  // stops growing); Compact() gives the memory back to the allocator. Each call is O(slots).

  /// Removes every live surfel of `submap_id` from the map and its spatial index. When `removed` is
  /// not null the removed surfels are appended to it (e.g. to spill the submap to disk). The other
  /// surfels keep their ids. Returns how many were removed (0 for an unknown submap).
  size_t RemoveSubmap(int32_t submap_id, std::vector<Surfel>* removed = nullptr);
  /// Removes the surfels of every submap not listed in `keep` (any order, duplicates allowed), as
  /// RemoveSubmap. Returns how many were removed.
  size_t RemoveSubmapsExcept(const std::vector<int32_t>& keep,
                             std::vector<Surfel>* removed = nullptr);
  /// Live surfel count per submap id, sorted by id (submaps without live surfels are not listed).
  std::vector<std::pair<int32_t, size_t>> SubmapSizes() const;
  /// Gives memory back: renumbers the live surfels 0 .. size()-1 (keeping their relative order),
  /// rebuilds the spatial index and shrinks the slot, flag and index storage to fit. INVALIDATES
  /// every surfel id held outside the map (ids from SelectActive, AddSurfels, rendered images).
  /// Returns the bytes released (MemoryBytes() before minus after; 0 when nothing was freed).
  size_t Compact();
  /// Adds surfels as they are (e.g. from another map); returns their ids. Invalid ones (non-finite,
  /// radius <= 0, normal not unit) are rejected with InvalidArgument before anything is added.
  StatusOr<std::vector<uint32_t>> AddSurfels(const std::vector<Surfel>& surfels);
  void Clear();

  /// Binary little-endian file: magic "SLMMSURF", version, record size, count, submap id, frame
  /// count, the live surfels (64-byte records), FNV-1a 64 checksum of all preceding bytes.
  [[nodiscard]] Status Save(const std::string& path) const;
  /// Replaces the contents with a saved map. NotFound / DataLoss (truncated, bad magic, version,
  /// checksum or values) leave the map unchanged.
  [[nodiscard]] Status Load(const std::string& path);

 private:
  struct Impl;
  explicit SurfelMap(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
