#pragma once
// Surfel: one oriented disc of the surfel map (paper §5.1.2; SuMa, Behley & Stachniss 2018).
//
// Positions and normals are in the frame of the SurfelMap that holds them ("world"); a submap's
// surfels can be moved rigidly with SurfelMap::TransformSubmap after a pose-graph correction.
// The renderers read position, radius and normal only (EglSurfelRenderer packs them with the id
// into a 32-byte vertex per surfel); the struct is 64 bytes, also the record size of SurfelMap
// files.
//
// Thread safety: value type.

#include <Eigen/Core>
#include <cstdint>
#include <type_traits>

namespace slam_mms {

struct Surfel {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< Disc centre in the map frame [m].
  float radius = 0.0f;                                 ///< Disc radius [m].
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();   ///< Unit normal in the map frame.
  float confidence = 0.0f;    ///< Stability log-odds l (SuMa): > 0 stable, < 0 unstable.
  int64_t created_ns = 0;     ///< Stamp of the scan that created it [ns since epoch].
  int64_t updated_ns = 0;     ///< Stamp of the last scan that confirmed it [ns since epoch].
  int32_t created_frame = 0;  ///< SurfelMap integration counter at creation.
  int32_t updated_frame = 0;  ///< Integration counter of the last confirmation.
  int32_t submap_id = 0;      ///< Submap it belongs to (SurfelMap::SetSubmapId at creation).
  int32_t num_updates = 0;    ///< Number of confirming measurements after creation.
};

static_assert(sizeof(Surfel) == 64, "Surfel is a 64-byte record");

/// Moves a surfel by the rigid transform (R, t): position R p + t, normal R n (re-normalised).
inline void TransformSurfel(const Eigen::Matrix3f& R, const Eigen::Vector3f& t, Surfel* s) {
  s->position = R * s->position + t;
  s->normal = (R * s->normal).normalized();
}

}  // namespace slam_mms
