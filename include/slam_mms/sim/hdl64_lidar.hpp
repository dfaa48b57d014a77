#pragma once
// Hdl64Lidar: a Velodyne HDL-64E model as in KITTI raw. Every firing is cast at its own time from
// the lidar pose on the TRUE trajectory, so a scan is skewed exactly like a raw KITTI scan: points
// are expressed in the lidar frame of their own firing time, time offsets run from the scan start.
//
// Geometry: 64 beams (uniform +2.0 .. -24.8 deg, or a table), `firings_per_revolution` firings per
// beam, clockwise seen from above starting and ending behind the car: firing j of the scan has
// azimuth atan2(y, x) = pi - 2 pi j / N and time offset j / (N * rate), which is KITTI's
// t = 0.5 (-atan2(y, x) / pi + 1) convention. Range noise is Gaussian; returns beyond max_range or
// grazing the surface (|cos incidence| < min_cos_incidence) are lost; reflectance =
// albedo (0.3 + 0.7 |cos incidence|) + noise, clamped to [0, 1]; returns are randomly lost more
// often on dark and distant surfaces (see Options::dropout_*). An optional elevation bias writes
// every point `elevation_bias_deg` lower than the ray that produced it (KITTI's 0.205 deg defect).
// Points are stored ring by ring (top beam first), each ring in firing order.
//
// Optional realism models (all off by default; docs/simulator.md "Realism models"):
// - Per-laser intrinsic calibration residuals (laser_*_sigma_*): each laser's true beam points
//   (d_elevation, d_azimuth) away from the nominal direction the point is written with, and its
//   range reads (1 + range_scale) r + range_offset. The 4 x num_beams residuals are drawn from the
//   `seed` passed to Simulate (not the scan index), so they are fixed for a drive (LaserErrors).
// - Beam divergence (beam_divergence_rad > 0): where a return's range differs from a neighbour's
//   (same ring, next firing, or same firing, next ring) by more than a depth-edge threshold and
//   the neighbour lies off the return's tangent plane (see mixed_pixel_edge_threshold_m), the
//   footprint is sampled with 7 sub-rays (centre and a hexagon at 2/3 of the footprint radius)
//   and the echoes are merged: within mixed_pixel_max_separation_m of each other the range is their
//   energy-weighted mean (albedo |cos| / r^2), a mixed pixel between foreground and background;
//   otherwise the strongest echo's group wins.
//
// Noise is drawn from a counter-based hash of (seed, scan, beam, firing): results do not depend on
// the number of threads. Thread safety: const methods may be called concurrently.

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/sim/city_world.hpp"
#include "slam_mms/sim/reference_trajectory.hpp"

namespace slam_mms::sim {

class Hdl64Lidar {
 public:
  struct Options {
    int num_beams = 64;
    double elevation_max_deg = 2.0;  ///< Uniform table from max down to min.
    double elevation_min_deg = -24.8;
    /// Explicit per-beam elevations [deg] (top first); overrides the uniform table when not empty.
    std::vector<double> elevation_table_deg;
    int firings_per_revolution = 2083;
    double rotation_rate_hz = 10.0;
    double range_noise_sigma_m = 0.02;
    double min_range_m = 2.0;  ///< Returns closer than this are dropped (the car itself).
    double max_range_m = 120.0;
    double min_cos_incidence = 0.02;  ///< Grazing returns below this are lost.
    double reflectance_noise_sigma = 0.02;
    double elevation_bias_deg = 0.0;  ///< KITTI-like: 0.205 (points written this much too low).
    /// Lost returns: probability dropout_base + dropout_far * (1 - albedo) * clamp((r - 30) / 90,
    /// 0, 1) (dark and distant surfaces return less often, as in KITTI's ~115-125k points a scan).
    double dropout_base = 0.03;
    double dropout_far = 0.6;

    /// Per-laser intrinsic calibration residuals, 1 sigma (0 = off). Published HDL-64E
    /// calibrations leave a few hundredths of a degree and a few cm (docs/simulator.md).
    double laser_elevation_sigma_deg = 0.0;
    double laser_azimuth_sigma_deg = 0.0;
    double laser_range_offset_sigma_m = 0.0;
    double laser_range_scale_sigma = 0.0;  ///< Relative (1e-3 = 1 mm per m).
    /// Full-angle beam divergence [rad] (0 = off; HDL-64E about 2e-3): mixed pixels at depth edges.
    double beam_divergence_rad = 0.0;
    /// Echoes of one footprint closer than this in range merge into one return [m].
    double mixed_pixel_max_separation_m = 5.0;
    /// A neighbour farther than this in range (plus 2 % of the range) and off the tangent plane by
    /// more than 0.1 m + 0.5 % of the range marks a depth edge [m].
    double mixed_pixel_edge_threshold_m = 0.3;

    /// The values docs/simulator.md gives for a factory-calibrated HDL-64E: per-laser residuals
    /// 0.03 deg (elevation and azimuth), 2 cm range offset, 1e-3 range scale.
    void EnableLaserIntrinsicErrors();

    [[nodiscard]] Status Validate() const;
  };

  /// One laser's calibration residual (truth minus what the point is written with).
  struct LaserError {
    double elevation_deg = 0.0;  ///< The true beam points this much higher.
    double azimuth_deg = 0.0;    ///< ... and this much further counter-clockwise (atan2(y, x)).
    double range_offset_m = 0.0;
    double range_scale = 0.0;  ///< Range read = (1 + range_scale) r_true + range_offset_m.
  };

  /// One simulated scan and, for the ground truth, the exact (noise-free) world hits.
  struct Output {
    Scan scan;  ///< Points in the lidar frame, per-point times.
    /// Same order as the scan's points: where the beam's centre ray truly met the scene (inside a
    /// scattering volume: the return's point there). Not the measurement: calibration residuals,
    /// noise and mixed-pixel blending move the scan's point away from it.
    std::vector<Eigen::Vector3f> p_world_exact;
    std::vector<SurfaceClass> surfaces;  ///< Same order.
    std::vector<uint8_t> beams;          ///< Beam (ring) index of each point, 0 = top.
  };

  Hdl64Lidar();
  explicit Hdl64Lidar(const Options& options);  ///< Call options.Validate() first.

  /// Simulates the revolution starting at `t_start_s` (trajectory seconds). `T_body_lidar` is the
  /// lidar mount; `scan_index` and `seed` select the noise; `num_threads` >= 1.
  Output Simulate(const CityWorld& world, const ReferenceTrajectory& trajectory,
                  const Eigen::Isometry3d& T_body_lidar, double t_start_s, int64_t scan_index,
                  uint64_t seed, int num_threads) const;

  /// Scan period [s] and the time offset of the last firing from the first.
  double PeriodSeconds() const { return 1.0 / options_.rotation_rate_hz; }
  double LastFiringOffsetSeconds() const;
  const std::vector<double>& elevations_deg() const { return elevations_deg_; }
  /// The per-laser residuals Simulate uses for `seed` (all zero where the sigmas are zero).
  std::vector<LaserError> LaserErrors(uint64_t seed) const;
  const Options& options() const { return options_; }

 private:
  struct Echo;
  static void MergeEchoes(Echo* echoes, int n, int num_samples, double max_separation_m,
                          double* range, double* shaded, SurfaceClass* surface);

  Options options_;
  std::vector<double> elevations_deg_;
};

}  // namespace slam_mms::sim
