#include "slam_mms/surfel/vertex_normal_map.hpp"

#include <algorithm>

namespace slam_mms {

void VertexNormalMap::Reset(int new_rows, int new_cols) {
  rows = std::max(new_rows, 0);
  cols = std::max(new_cols, 0);
  const size_t n = static_cast<size_t>(rows) * static_cast<size_t>(cols);
  vertex.resize(n);
  normal.resize(n);
  range.resize(n);
  index.resize(n);
  Clear();
}

void VertexNormalMap::Clear() {
  std::fill(vertex.begin(), vertex.end(), Eigen::Vector3f::Zero());
  std::fill(normal.begin(), normal.end(), Eigen::Vector3f::Zero());
  std::fill(range.begin(), range.end(), 0.0f);
  std::fill(index.begin(), index.end(), -1);
}

int VertexNormalMap::CountVertices() const {
  int n = 0;
  for (int i = 0; i < size(); ++i) n += HasVertex(i) ? 1 : 0;
  return n;
}

int VertexNormalMap::CountNormals() const {
  int n = 0;
  for (int i = 0; i < size(); ++i) n += (HasVertex(i) && HasNormal(i)) ? 1 : 0;
  return n;
}

}  // namespace slam_mms
