#pragma once
// PathIndex: the driven path as a 2D polyline with per-sample street attributes, and
// nearest-segment queries on a dense coarse grid. Private to the simulator.
#include <Eigen/Core>
#include <vector>

namespace slam_mms::sim {

struct PathSample {
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  double z_road = 0.0;  // road surface height at the path [m]
  Eigen::Vector2d tangent = Eigen::Vector2d::UnitX();
  double s = 0.0;            // arc length [m]
  double s_canonical = 0.0;  // arc length of the first pass over this street (markings)
  double half_width = 5.0;   // road half width [m]
  double sidewalk = 3.0;     // sidewalk width [m]
  int street = 0;
  bool revisit = false;  // lies on a street driven before
  // +1, or -1 on a revisit driven against the first pass (s_canonical decreases along s).
  double canonical_sign = 1.0;
  // First sample of a separate path (several paths of one city): no segment joins it to the
  // sample before.
  bool path_start = false;
  // On the straight extension beyond a path's end (not driven; z_road is the end's).
  bool extension = false;
};

struct PathNearest {
  double distance = 1e30;
  int segment = -1;    // segment i joins samples i and i+1
  double alpha = 0.0;  // position along the segment in [0, 1]
  Eigen::Vector2d foot = Eigen::Vector2d::Zero();
};

// Segment i joins samples i and i + 1 unless sample i + 1 starts a separate path.
class PathIndex {
 public:
  PathIndex() = default;
  PathIndex(std::vector<PathSample> samples, double cell_m, double margin_m);

  /// Nearest point of the polyline within `max_distance` (distance 1e30 where none).
  PathNearest Nearest(const Eigen::Vector2d& q, double max_distance) const;
  /// Attributes interpolated at a nearest-point result.
  double ZRoad(const PathNearest& n) const;
  double SCanonical(const PathNearest& n) const;
  const PathSample& SampleOf(const PathNearest& n) const {
    return samples_[n.alpha < 0.5 ? n.segment : n.segment + 1];
  }

  const std::vector<PathSample>& samples() const { return samples_; }
  Eigen::Vector2d min() const { return min_; }
  Eigen::Vector2d max() const { return max_; }

 private:
  std::vector<PathSample> samples_;
  double cell_ = 8.0;
  Eigen::Vector2d min_ = Eigen::Vector2d::Zero(), max_ = Eigen::Vector2d::Zero();
  int nx_ = 0, ny_ = 0;
  std::vector<int> cell_start_;  // CSR over cells
  std::vector<int> cell_segments_;
};

}  // namespace slam_mms::sim
