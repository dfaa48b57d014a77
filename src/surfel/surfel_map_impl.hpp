#pragma once
// SurfelMap's private state (shared by surfel_map.cpp and surfel_map_io.cpp).
#include <memory>
#include <vector>

#include "core/worker_pool.hpp"
#include "slam_mms/surfel/surfel_map.hpp"
#include "surfel/cpu_surfel_renderer.hpp"
#include "surfel/surfel_projection_block.hpp"
#include "surfel/voxel_index.hpp"

namespace slam_mms {

struct SurfelMap::Impl {
  Impl(const SurfelMapOptions& o, int num_threads);

  /// Appends or reuses a slot; returns the id.
  uint32_t AddSlot(const Surfel& s);
  void RemoveSlot(uint32_t id);

  // Integrate's stages after the model render (surfel_map_integrate.cpp).
  /// 3. Per pixel: explained by the rendered surfel, or a conflict (the ray passed through it).
  void ClassifyPixels(const VertexNormalMap& scan, SurfelIntegrationStats* stats);
  /// 4-5. Per active surfel: confirm and refine, or penalise a conflict; remove unstable ones.
  void UpdateActiveSurfels(const VertexNormalMap& scan, const Eigen::Isometry3d& T_world_sensor,
                           Timestamp stamp, SurfelIntegrationStats* stats);
  /// 6. New surfels for the unexplained pixels with a normal facing the sensor.
  void CreateSurfels(const VertexNormalMap& scan, const Eigen::Isometry3d& T_world_sensor,
                     Timestamp stamp, SurfelIntegrationStats* stats);

  SurfelMapOptions options;
  std::vector<Surfel> surfels;
  std::vector<uint8_t> alive;
  std::vector<uint32_t> free_ids;
  size_t num_alive = 0;
  internal::VoxelIndex index;
  int32_t submap_id = 0;
  int32_t frame_count = 0;
  std::unique_ptr<CpuSurfelRenderer> own_renderer;
  SurfelRenderer* renderer = nullptr;
  internal::WorkerPool pool;
  // Scratch reused across Integrate calls.
  std::vector<uint32_t> active;
  std::vector<uint32_t> candidates;
  VertexNormalMap model;
  enum PixelState : uint8_t { kNone = 0, kExplained = 1, kConflict = 2 };
  std::vector<uint8_t> pixel_state;  // PixelState per pixel
  std::vector<uint8_t> conflict;     // by surfel id
  std::vector<std::vector<uint32_t>> removed_per_thread;
  std::vector<std::vector<uint32_t>> moved_per_thread;
  std::vector<std::vector<int>> integrated_per_thread;  // pixels confirmed by a surfel centre
  std::vector<int> confirmed_per_thread;
  std::vector<size_t> kept_per_thread;                             // SelectActive
  std::vector<internal::SurfelProjectionBlock> projection_blocks;  // per thread, Integrate
};

}  // namespace slam_mms
