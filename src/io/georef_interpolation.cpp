// GeoReference::EnuToProjectedInterpolated: the map projection of the LAS writer, exact (PROJ,
// through EnuToProjected) at the corners of the cells that hold points, trilinear inside a cell.
// The cells are the library's one voxel-cell arithmetic (core/voxel_grid.hpp).
#include <cmath>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/voxel_grid.hpp"
#include "slam_mms/io/georef.hpp"

namespace slam_mms {

Status GeoReference::EnuToProjectedInterpolated(const std::vector<Eigen::Vector3d>& p_world,
                                                std::vector<Eigen::Vector3d>* out,
                                                double cell_m) const {
  if (!(cell_m > 0.0) || !std::isfinite(cell_m)) {
    return InvalidArgumentError("GeoReference: interpolation cell " + std::to_string(cell_m) +
                                " m; must be finite and > 0");
  }
  const size_t n = p_world.size();
  out->resize(n);
  if (n == 0) return OkStatus();
  // The occupied cells, numbered in order of first appearance. A map comes in voxel order, so
  // consecutive points mostly share a cell: the table is asked only where the cell changes.
  const internal::VoxelGrid grid(cell_m);
  std::unordered_map<internal::VoxelCell, uint32_t, internal::VoxelCellHash> cell_number;
  std::vector<internal::VoxelCell> cells;
  std::vector<uint32_t> point_cell(n);
  internal::VoxelCell last;
  for (size_t i = 0; i < n; ++i) {
    internal::VoxelCell c;
    if (!grid.CellOf(p_world[i], &c)) {
      return InvalidArgumentError(
          "GeoReference: point " + std::to_string(i) +
          (p_world[i].allFinite() ? " is too far from the origin" : " is not finite"));
    }
    if (cells.empty() || c != last) {
      const auto [it, added] = cell_number.try_emplace(c, static_cast<uint32_t>(cells.size()));
      if (added) cells.push_back(c);
      last = c;
      point_cell[i] = it->second;
    } else {
      point_cell[i] = point_cell[i - 1];
    }
  }
  // The 8 corners of every occupied cell (in x, y, z bit order), exactly; a corner shared by
  // neighbouring cells is computed once per cell: simpler, and still a few per cent of the points.
  std::vector<Eigen::Vector3d> corners_world;
  corners_world.reserve(8 * cells.size());
  for (const internal::VoxelCell& c : cells) {
    for (int k = 0; k < 8; ++k) {
      corners_world.push_back(
          grid.Corner({c.x + (k & 1), c.y + ((k >> 1) & 1), c.z + ((k >> 2) & 1)}));
    }
  }
  std::vector<Eigen::Vector3d> corners;
  SLAM_MMS_RETURN_IF_ERROR(EnuToProjected(corners_world, &corners));
  // Trilinear inside each cell, as offsets from its first corner (E and N are ~1e5..1e7 m).
  const double inv = 1.0 / cell_m;
  for (size_t i = 0; i < n; ++i) {
    const size_t c0 = 8 * static_cast<size_t>(point_cell[i]);
    const Eigen::Vector3d f = (p_world[i] - corners_world[c0]) * inv;
    const Eigen::Vector3d* v = &corners[c0];
    const Eigen::Vector3d d1 = v[1] - v[0], d2 = v[2] - v[0], d3 = v[3] - v[0];
    const Eigen::Vector3d d4 = v[4] - v[0], d5 = v[5] - v[0], d6 = v[6] - v[0];
    const Eigen::Vector3d d7 = v[7] - v[0];
    const double x = f.x(), y = f.y(), z = f.z();
    const Eigen::Vector3d lower = (1.0 - y) * (x * d1) + y * ((1.0 - x) * d2 + x * d3);
    const Eigen::Vector3d upper =
        (1.0 - y) * ((1.0 - x) * d4 + x * d5) + y * ((1.0 - x) * d6 + x * d7);
    (*out)[i] = v[0] + ((1.0 - z) * lower + z * upper);
  }
  return OkStatus();
}

}  // namespace slam_mms
