#include "sim/city_path.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "sim/random.hpp"

namespace slam_mms::sim {
namespace {

constexpr double kSampleSpacing_m = 0.5;
constexpr double kExtension_m = 80.0;  // streets continue beyond the drive's ends

}  // namespace

std::vector<PathSample> SamplePath(const ReferenceTrajectory& traj, double t_begin, double t_end,
                                   double body_height) {
  std::vector<PathSample> out;
  auto add = [&](const Eigen::Vector3d& p) {
    PathSample s;
    s.p = p.head<2>();
    s.z_road = p.z() - body_height;
    out.push_back(s);
  };
  Eigen::Vector3d last = traj.Pose(t_begin).translation();
  add(last);
  for (double t = t_begin; t <= t_end; t += 0.02) {
    const Eigen::Vector3d p = traj.Pose(t).translation();
    if ((p - last).head<2>().norm() >= kSampleSpacing_m) {
      add(p);
      last = p;
    }
  }
  if (out.size() < 2) {  // the vehicle does not move: a street along its heading
    const Eigen::Matrix3d R = traj.Pose(t_begin).linear();
    Eigen::Vector3d p = out.front().p.homogeneous();
    p.z() = last.z();
    add(p + Eigen::Vector3d(R(0, 0), R(1, 0), 0.0).normalized() * kSampleSpacing_m);
  }
  // Tangents, then straight extensions before the start and after the end.
  auto tangent_at = [&](size_t i) {
    const size_t a = i == 0 ? 0 : i - 1, b = std::min(out.size() - 1, i + 1);
    Eigen::Vector2d d = out[b].p - out[a].p;
    return d.norm() > 1e-9 ? Eigen::Vector2d(d.normalized()) : Eigen::Vector2d::UnitX();
  };
  for (size_t i = 0; i < out.size(); ++i) out[i].tangent = tangent_at(i);
  std::vector<PathSample> ext;
  const int n_ext = static_cast<int>(kExtension_m / kSampleSpacing_m);
  for (int k = n_ext; k >= 1; --k) {
    PathSample s = out.front();
    s.p -= s.tangent * (k * kSampleSpacing_m);
    s.extension = true;
    ext.push_back(s);
  }
  ext.insert(ext.end(), out.begin(), out.end());
  for (int k = 1; k <= n_ext; ++k) {
    PathSample s = out.back();
    s.p += s.tangent * (k * kSampleSpacing_m);
    s.extension = true;
    ext.push_back(s);
  }
  double s_acc = 0.0;
  for (size_t i = 0; i < ext.size(); ++i) {
    if (i > 0) s_acc += (ext[i].p - ext[i - 1].p).norm();
    ext[i].s = ext[i].s_canonical = s_acc;
  }
  return ext;
}

std::vector<PathSample> SamplePaths(const std::vector<CityWorld::PathSpan>& spans,
                                    double body_height) {
  constexpr double kGap_m = 100.0;  // > AssignStreets' 40 m: no revisit is missed at a join
  std::vector<PathSample> out;
  for (const CityWorld::PathSpan& span : spans) {
    std::vector<PathSample> path =
        SamplePath(*span.trajectory, span.t_begin_s, span.t_end_s, body_height);
    const double offset = out.empty() ? 0.0 : out.back().s + kGap_m;
    for (PathSample& p : path) {
      p.s += offset;
      p.s_canonical += offset;
    }
    path.front().path_start = true;
    out.insert(out.end(), path.begin(), path.end());
  }
  return out;
}

void MatchExtensionHeights(std::vector<PathSample>* samples) {
  std::unordered_map<int64_t, std::vector<int>> grid;  // driven samples, 4 m cells
  auto key = [](int64_t x, int64_t y) {
    return static_cast<int64_t>((static_cast<uint64_t>(x) << 32) ^
                                static_cast<uint64_t>(y & 0xffffffffLL));
  };
  auto cell = [](double v) { return static_cast<int64_t>(std::floor(v / 4.0)); };
  for (size_t i = 0; i < samples->size(); ++i) {
    const PathSample& s = (*samples)[i];
    if (!s.extension) grid[key(cell(s.p.x()), cell(s.p.y()))].push_back(static_cast<int>(i));
  }
  for (PathSample& s : *samples) {
    if (!s.extension) continue;
    double best = 2.5;
    const PathSample* driven = nullptr;
    for (int64_t dx = -1; dx <= 1; ++dx) {
      for (int64_t dy = -1; dy <= 1; ++dy) {
        auto it = grid.find(key(cell(s.p.x()) + dx, cell(s.p.y()) + dy));
        if (it == grid.end()) continue;
        for (int j : it->second) {
          const PathSample& e = (*samples)[j];
          const double d = (e.p - s.p).norm();
          if (d < best && std::abs(e.tangent.dot(s.tangent)) > 0.8) {
            best = d;
            driven = &e;
          }
        }
      }
    }
    if (driven != nullptr) s.z_road = driven->z_road;
  }
}

void AssignStreets(const CityWorld::Options& o, bool either_direction,
                   std::vector<PathSample>* samples) {
  Rng rng(MixSeed(o.seed, 1));
  int street = -1;
  Eigen::Vector2d street_dir = Eigen::Vector2d::Zero();
  double w = 0, sw = 0;
  // Coarse hash of earlier samples to detect revisits of a street (same direction, within 2.5 m).
  std::unordered_map<int64_t, std::vector<int>> grid;
  auto key = [](const Eigen::Vector2d& p) {
    const int64_t x = static_cast<int64_t>(std::floor(p.x() / 4.0));
    const int64_t y = static_cast<int64_t>(std::floor(p.y() / 4.0));
    // Shift as unsigned: x << 32 of a negative x is undefined in C++17 (UBSan); same bits.
    return static_cast<int64_t>((static_cast<uint64_t>(x) << 32) ^
                                static_cast<uint64_t>(y & 0xffffffffLL));
  };
  for (size_t i = 0; i < samples->size(); ++i) {
    PathSample& s = (*samples)[i];
    if (s.path_start) street_dir = Eigen::Vector2d::Zero();  // a new path: a new street
    int earlier = -1;
    double best = 2.5;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        auto it = grid.find(key(s.p + Eigen::Vector2d(4.0 * dx, 4.0 * dy)));
        if (it == grid.end()) continue;
        for (int j : it->second) {
          const PathSample& e = (*samples)[j];
          const double d = (e.p - s.p).norm();
          const double dot = e.tangent.dot(s.tangent);
          if (e.s < s.s - 40.0 && d < best && (dot > 0.8 || (either_direction && dot < -0.8))) {
            best = d;
            earlier = j;
          }
        }
      }
    }
    if (earlier >= 0) {
      const PathSample& e = (*samples)[earlier];
      s.half_width = e.half_width;
      s.sidewalk = e.sidewalk;
      s.street = e.street;
      s.s_canonical = e.s_canonical + (s.p - e.p).dot(e.tangent);
      s.canonical_sign = e.tangent.dot(s.tangent) > 0.0 ? 1.0 : -1.0;
      s.revisit = true;
      street_dir = Eigen::Vector2d::Zero();  // a new street starts after the revisit
    } else {
      if (street < 0 || street_dir.dot(s.tangent) < std::cos(50.0 * M_PI / 180.0)) {
        ++street;
        street_dir = s.tangent;
        w = rng.Uniform(o.road_half_width_min_m, o.road_half_width_max_m);
        sw = rng.Uniform(o.sidewalk_width_min_m, o.sidewalk_width_max_m);
      }
      s.half_width = w;
      s.sidewalk = sw;
      s.street = street;
      if (i > 0 && (*samples)[i - 1].revisit) {
        s.s_canonical = (*samples)[i - 1].s_canonical + ((*samples)[i].s - (*samples)[i - 1].s);
      } else if (i > 0) {
        s.s_canonical = (*samples)[i - 1].s_canonical + (s.s - (*samples)[i - 1].s);
      }
      grid[key(s.p)].push_back(static_cast<int>(i));
    }
  }
}

}  // namespace slam_mms::sim
