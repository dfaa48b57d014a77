#include "sim/path_index.hpp"

#include <algorithm>
#include <cmath>

namespace slam_mms::sim {

PathIndex::PathIndex(std::vector<PathSample> samples, double cell_m, double margin_m)
    : samples_(std::move(samples)), cell_(cell_m) {
  min_ = max_ = samples_.front().p;
  for (const auto& s : samples_) {
    min_ = min_.cwiseMin(s.p);
    max_ = max_.cwiseMax(s.p);
  }
  min_ -= Eigen::Vector2d::Constant(margin_m);
  max_ += Eigen::Vector2d::Constant(margin_m);
  nx_ = static_cast<int>(std::ceil((max_.x() - min_.x()) / cell_)) + 1;
  ny_ = static_cast<int>(std::ceil((max_.y() - min_.y()) / cell_)) + 1;
  std::vector<std::vector<int>> cells(static_cast<size_t>(nx_) * ny_);
  for (size_t i = 0; i + 1 < samples_.size(); ++i) {
    if (samples_[i + 1].path_start) continue;  // no segment between two separate paths
    const Eigen::Vector2d a = samples_[i].p.cwiseMin(samples_[i + 1].p) - min_;
    const Eigen::Vector2d b = samples_[i].p.cwiseMax(samples_[i + 1].p) - min_;
    for (int cy = static_cast<int>(a.y() / cell_); cy <= static_cast<int>(b.y() / cell_); ++cy)
      for (int cx = static_cast<int>(a.x() / cell_); cx <= static_cast<int>(b.x() / cell_); ++cx)
        cells[static_cast<size_t>(cy) * nx_ + cx].push_back(static_cast<int>(i));
  }
  cell_start_.assign(cells.size() + 1, 0);
  for (size_t c = 0; c < cells.size(); ++c)
    cell_start_[c + 1] = cell_start_[c] + static_cast<int>(cells[c].size());
  cell_segments_.reserve(cell_start_.back());
  for (const auto& c : cells) cell_segments_.insert(cell_segments_.end(), c.begin(), c.end());
}

PathNearest PathIndex::Nearest(const Eigen::Vector2d& q, double max_distance) const {
  PathNearest best;
  if (samples_.size() < 2) return best;
  const int cx = static_cast<int>(std::floor((q.x() - min_.x()) / cell_));
  const int cy = static_cast<int>(std::floor((q.y() - min_.y()) / cell_));
  const int max_ring = static_cast<int>(std::ceil(max_distance / cell_)) + 1;
  auto visit = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= nx_ || y >= ny_) return;
    const size_t c = static_cast<size_t>(y) * nx_ + x;
    for (int k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
      const int i = cell_segments_[k];
      const Eigen::Vector2d a = samples_[i].p, d = samples_[i + 1].p - a;
      const double len2 = d.squaredNorm();
      const double t = len2 > 0 ? std::clamp((q - a).dot(d) / len2, 0.0, 1.0) : 0.0;
      const Eigen::Vector2d f = a + t * d;
      const double dist = (q - f).norm();
      if (dist < best.distance || (dist == best.distance && i < best.segment)) {
        best.distance = dist;
        best.segment = i;
        best.alpha = t;
        best.foot = f;
      }
    }
  };
  for (int r = 0; r <= max_ring; ++r) {
    if (r == 0) {
      visit(cx, cy);
    } else {
      for (int x = cx - r; x <= cx + r; ++x) {
        visit(x, cy - r);
        visit(x, cy + r);
      }
      for (int y = cy - r + 1; y <= cy + r - 1; ++y) {
        visit(cx - r, y);
        visit(cx + r, y);
      }
    }
    if (best.distance <= r * cell_) break;
  }
  if (best.distance > max_distance) return PathNearest{};
  return best;
}

double PathIndex::ZRoad(const PathNearest& n) const {
  return (1.0 - n.alpha) * samples_[n.segment].z_road + n.alpha * samples_[n.segment + 1].z_road;
}

double PathIndex::SCanonical(const PathNearest& n) const {
  const auto& a = samples_[n.segment];
  const auto& b = samples_[n.segment + 1];
  return a.s_canonical + n.alpha * (a.canonical_sign * (b.s - a.s));
}

}  // namespace slam_mms::sim
