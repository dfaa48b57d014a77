// The embedded default urban drive: a block loop with a revisit of its first street.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "slam_mms/sim/reference_trajectory.hpp"

namespace slam_mms::sim {
namespace {

struct PathPoint {
  Eigen::Vector2d p;
  double heading = 0.0;    // [rad]
  double curvature = 0.0;  // [1/m], + = left turn
  double v_limit = 0.0;    // [m/s]
};

constexpr double kBodyHeightAboveRoad_m = 0.93;  // KITTI: Velodyne 1.73 m, IMU 0.80 m below it.
constexpr double kStep_m = 0.05;

// Gentle road height profile in the city frame [m].
double RoadHeight(const Eigen::Vector2d& p) {
  return 2.5 * std::sin(2.0 * M_PI * p.x() / 600.0) +
         1.5 * std::sin(2.0 * M_PI * p.y() / 450.0 + 1.0);
}

struct Leg {
  Eigen::Vector2d start;
  double cruise_mps;
};

// Pose samples at 10 Hz along the polyline of `legs` (corners rounded, the last leg's start is the
// end), with standstills at the arc lengths in `stops` ({metres along the path, dwell seconds}).
std::vector<PoseSample> RouteSamples(const std::vector<Leg>& legs,
                                     const std::vector<std::pair<double, double>>& stop_at) {
  const double corner_radius_m = 11.0;
  const double lateral_accel_mps2 = 2.0;
  const double accel_mps2 = 1.2, decel_mps2 = 1.6;

  // Dense path with arcs at the corners.
  std::vector<PathPoint> path;
  auto add_line = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b, double v) {
    const Eigen::Vector2d d = b - a;
    const double len = d.norm();
    const double heading = std::atan2(d.y(), d.x());
    const int n = std::max(1, static_cast<int>(std::round(len / kStep_m)));
    for (int i = 0; i < n; ++i)
      path.push_back({a + d * (static_cast<double>(i) / n), heading, 0.0, v});
  };
  Eigen::Vector2d cursor = legs[0].start;
  for (size_t i = 1; i + 1 < legs.size(); ++i) {
    const Eigen::Vector2d c = legs[i].start;
    const Eigen::Vector2d d_in = (c - legs[i - 1].start).normalized();
    const Eigen::Vector2d d_out = (legs[i + 1].start - c).normalized();
    const double turn = std::atan2(d_in.x() * d_out.y() - d_in.y() * d_out.x(), d_in.dot(d_out));
    const double tangent = corner_radius_m * std::tan(std::abs(turn) / 2.0);
    add_line(cursor, c - d_in * tangent, legs[i - 1].cruise_mps);
    // Arc.
    const double sign = turn > 0 ? 1.0 : -1.0;
    const Eigen::Vector2d normal(-d_in.y() * sign, d_in.x() * sign);
    const Eigen::Vector2d center = c - d_in * tangent + normal * corner_radius_m;
    const double h0 = std::atan2(d_in.y(), d_in.x());
    const double arc_len = corner_radius_m * std::abs(turn);
    const int n = std::max(1, static_cast<int>(std::round(arc_len / kStep_m)));
    const double v_corner = std::sqrt(lateral_accel_mps2 * corner_radius_m);
    for (int k = 0; k < n; ++k) {
      const double h = h0 + turn * k / n;
      const Eigen::Vector2d radial(std::sin(h) * sign, -std::cos(h) * sign);
      path.push_back({center + radial * corner_radius_m, h, sign / corner_radius_m, v_corner});
    }
    cursor = c + d_out * tangent;
  }
  add_line(cursor, legs.back().start, legs[legs.size() - 2].cruise_mps);
  path.push_back({legs.back().start, path.back().heading, 0.0, 0.0});

  // Speed profile: limits, stops (traffic lights), acceleration limits by forward/backward passes.
  const size_t m = path.size();
  std::vector<double> v(m);
  for (size_t i = 0; i < m; ++i) v[i] = path[i].v_limit;
  std::vector<std::pair<size_t, double>> stops;  // index, dwell [s]
  auto index_at = [&](double s) { return std::min(m - 1, static_cast<size_t>(s / kStep_m)); };
  for (const auto& [s_m, dwell_s] : stop_at) stops.push_back({index_at(s_m), dwell_s});
  v.front() = 0.0;
  v.back() = 0.0;
  for (auto& s : stops) v[s.first] = 0.0;
  for (size_t i = 1; i < m; ++i)
    v[i] = std::min(v[i], std::sqrt(v[i - 1] * v[i - 1] + 2.0 * accel_mps2 * kStep_m));
  for (size_t i = m - 1; i-- > 0;)
    v[i] = std::min(v[i], std::sqrt(v[i + 1] * v[i + 1] + 2.0 * decel_mps2 * kStep_m));

  // Time along the path, with 2 s standstill at the start, the stop dwells and 1 s at the end.
  std::vector<double> t(m, 0.0);
  double time = 2.0;
  size_t next_stop = 0;
  for (size_t i = 0; i < m; ++i) {
    if (i > 0) time += 2.0 * kStep_m / std::max(v[i - 1] + v[i], 1e-3);
    if (next_stop < stops.size() && stops[next_stop].first == i) {
      time += stops[next_stop].second;
      ++next_stop;
    }
    t[i] = time;
  }
  // Samples at 10 Hz, interpolated along the path; accelerations from the speed profile.
  const double rotation = 20.0 * M_PI / 180.0;  // streets are not axis-aligned
  const Eigen::Rotation2Dd R(rotation);
  std::vector<PoseSample> out;
  const double t_end = t.back() + 1.0;
  size_t j = 0;
  for (int k = 0;; ++k) {
    const double tk = 0.1 * k;
    if (tk > t_end + 1e-9) break;
    while (j + 1 < m && t[j + 1] <= tk) ++j;
    double alpha = 0.0;
    if (j + 1 < m && tk > t[j]) alpha = std::clamp((tk - t[j]) / (t[j + 1] - t[j]), 0.0, 1.0);
    const size_t j1 = std::min(j + 1, m - 1);
    const Eigen::Vector2d p = path[j].p + alpha * (path[j1].p - path[j].p);
    double heading =
        path[j].heading + alpha * std::remainder(path[j1].heading - path[j].heading, 2 * M_PI);
    const double speed = v[j] + alpha * (v[j1] - v[j]);
    // Longitudinal acceleration from v dv/ds.
    const double a_long = (v[j1] * v[j1] - v[j] * v[j]) / (2.0 * kStep_m);
    const double a_lat = speed * speed * path[j].curvature;
    // Road slope along the heading.
    const Eigen::Vector2d dir(std::cos(heading), std::sin(heading));
    const double slope = (RoadHeight(p + 0.5 * dir) - RoadHeight(p - 0.5 * dir)) / 1.0;
    PoseSample sample;
    sample.t_s = tk;
    const Eigen::Vector2d pw = R * p;
    sample.p_world = Eigen::Vector3d(pw.x(), pw.y(), RoadHeight(p) + kBodyHeightAboveRoad_m);
    // KITTI: pitch + = front down; roll + = left side up. Braking dips the nose, turning left
    // rolls the body to the right (left side up).
    sample.rpy_rad =
        Eigen::Vector3d(0.004 * a_lat, -std::atan(slope) - 0.004 * a_long, heading + rotation);
    out.push_back(sample);
  }
  return out;
}

}  // namespace

std::vector<PoseSample> DefaultUrbanRouteSamples() {
  // Corners of the route in the city frame (x east-ish, y north-ish) with the cruise speed of the
  // leg that starts there: east along street A, north, west, south, east along A again (revisit),
  // then south into a new street.
  const std::vector<Leg> legs = {{{0.0, 0.0}, 9.5},     {{300.0, 0.0}, 10.0}, {{300.0, 200.0}, 8.5},
                                 {{-20.0, 200.0}, 9.0}, {{-20.0, 0.0}, 9.5},  {{150.0, 0.0}, 8.0},
                                 {{150.0, -160.0}, 0.0}};
  // Stops before the second corner and mid west street.
  return RouteSamples(legs, {{470.0, 6.0}, {860.0, 8.0}});
}

std::vector<PoseSample> DemoUrbanRouteSamples() {
  // One block (100 m x 70 m) driven anticlockwise, then its first street again (the revisit that
  // level 2 closes a loop on): four 90 deg turns, about 60 s of scans.
  const std::vector<Leg> legs = {{{0.0, 0.0}, 9.0},  {{100.0, 0.0}, 8.5}, {{100.0, 70.0}, 9.0},
                                 {{0.0, 70.0}, 8.5}, {{0.0, 0.0}, 8.0},   {{60.0, 0.0}, 0.0}};
  return RouteSamples(legs, {});
}

int NumRouteVariants(const std::string& scenario) {
  return scenario == "demo" || scenario == "default" ? 3 : 0;
}

StatusOr<std::vector<PoseSample>> RouteVariantSamples(const std::string& scenario, int variant) {
  const int n = NumRouteVariants(scenario);
  if (n == 0) {
    return InvalidArgumentError("RouteVariantSamples: scenario '" + scenario +
                                "' has no route variants (only \"demo\" and \"default\")");
  }
  if (variant < 0 || variant >= n) {
    return InvalidArgumentError("RouteVariantSamples: route_variant = " + std::to_string(variant) +
                                "; must be in [0, " + std::to_string(n) + ") for scenario '" +
                                scenario + "'");
  }
  // Corners in the city frame of DefaultUrbanRouteSamples / DemoUrbanRouteSamples (the same
  // rotation, road profile and origin): variant 0 is that route itself. docs/simulator.md
  // "Route variants" lists the streets each variant shares with the others.
  if (scenario == "demo") {
    if (variant == 0) return DemoUrbanRouteSamples();
    if (variant == 1) {
      // Clockwise around the double block x in [0, 100], y in [0, 140] from its north-west
      // corner: variant 0's east, first and west streets in the opposite direction, then 30 m
      // of its own first street again (a revisit).
      const std::vector<Leg> legs = {{{0.0, 140.0}, 9.0}, {{100.0, 140.0}, 8.5},
                                     {{100.0, 0.0}, 9.0}, {{0.0, 0.0}, 8.5},
                                     {{0.0, 140.0}, 8.0}, {{30.0, 140.0}, 0.0}};
      return RouteSamples(legs, {});
    }
    // Variant 2: from the south up variant 0's east street (same direction), clockwise around the
    // adjacent block x in [100, 200], y in [0, 70], west along variant 0's first street.
    const std::vector<Leg> legs = {{{100.0, -70.0}, 9.0},
                                   {{100.0, 70.0}, 8.5},
                                   {{200.0, 70.0}, 9.0},
                                   {{200.0, 0.0}, 8.5},
                                   {{40.0, 0.0}, 0.0}};
    return RouteSamples(legs, {});
  }
  if (variant == 0) return DefaultUrbanRouteSamples();
  if (variant == 1) {
    // From the north down variant 0's east street, then its first, west and (half) north streets
    // in the opposite direction, north into new streets and back to the start (a loop).
    const std::vector<Leg> legs = {
        {{300.0, 350.0}, 9.5}, {{300.0, 0.0}, 10.0},  {{-20.0, 0.0}, 9.0},  {{-20.0, 200.0}, 9.5},
        {{150.0, 200.0}, 8.5}, {{150.0, 350.0}, 9.0}, {{300.0, 350.0}, 0.0}};
    return RouteSamples(legs, {{420.0, 7.0}, {900.0, 6.0}});
  }
  // Variant 2: from the east along variant 0's first street (opposite direction), south down its
  // south street (same direction), around the block east of it and back down its east street.
  const std::vector<Leg> legs = {
      {{450.0, 0.0}, 9.5},   {{150.0, 0.0}, 9.0},   {{150.0, -160.0}, 10.0}, {{450.0, -160.0}, 9.5},
      {{450.0, 200.0}, 8.5}, {{300.0, 200.0}, 8.5}, {{300.0, 100.0}, 0.0}};
  return RouteSamples(legs, {{520.0, 8.0}, {1000.0, 6.0}});
}

std::vector<PoseSample> LongUrbanRouteSamples(double min_duration_s) {
  // A serpentine through a street grid: 420 m east, 120 m north, 420 m west, 120 m north, ...,
  // always into new streets, so the area mapped grows with the drive. A traffic-light stop every
  // fourth long street.
  constexpr double kStreet_m = 420.0, kBlock_m = 120.0, kMeanSpeed_mps = 8.0;
  const int num_streets = std::max(
      2, static_cast<int>(std::ceil(min_duration_s * kMeanSpeed_mps / (kStreet_m + kBlock_m))) + 1);
  std::vector<Leg> legs;
  std::vector<std::pair<double, double>> stops;
  const double speeds[] = {9.5, 10.0, 8.5, 9.0};
  for (int i = 0; i < num_streets; ++i) {
    const double y = i * kBlock_m;
    const bool east = i % 2 == 0;
    legs.push_back({{east ? 0.0 : kStreet_m, y}, speeds[i % 4]});
    legs.push_back({{east ? kStreet_m : 0.0, y}, 8.0});
    if (i % 4 == 1) stops.push_back({i * (kStreet_m + kBlock_m) + 0.5 * kStreet_m, 6.0});
  }
  legs.push_back({{legs.back().start.x(), num_streets * kBlock_m}, 0.0});
  return RouteSamples(legs, stops);
}

}  // namespace slam_mms::sim
