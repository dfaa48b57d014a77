#pragma once
// Scan statistics for comparing a simulated LiDAR drive with a real one (issue 16, the realism
// report): what a scan looks like, computed from the raw scan alone (lidar frame, no labels, no
// poses), so the same numbers come from real KITTI frames and from simulated ones.
//
// Per scan (ComputeScanStatistics), accumulated over a drive (ScanStatistics::Add):
// - points per scan; the range histogram (0..max_range_m, 2 m bins); the intensity histogram
//   (0..1, 20 bins);
// - rings: recovered from the point order (RecoverRings: a multi-beam scanner writes its points
//   ring by ring, each ring one revolution; the rotation direction is detected); the share of the
//   scan's points per ring and the range-image fill (rings x `range_image_columns` azimuth cells,
//   the fraction of cells with a return). Without recoverable rings (not `num_beams` +-2 of them)
//   both are left out and `rings_recovered_scans` says so;
// - local geometry from a PCA of the scan's points within `neighborhood_radius_m` of every
//   `query_stride`-th point (eigenvalues l0 <= l1 <= l2 of the covariance, normal n = eigenvector
//   of l0): the histogram of log10(l0) [m^2] (local planarity), of |n_z| (normal direction; for
//   neighbourhoods that are not a single line, l1 >= min_planar_extent * l2), and the share of
//   four geometric classes: ground (surface variation l0/(l0+l1+l2) < planar_max_variation, not a
//   line, |n_z| > 0.9, z < ground_max_z_m in the lidar frame), facade (same, |n_z| < 0.3), scatter
//   (surface variation > scatter_min_variation: vegetation and clutter) and other (the rest, and
//   queries with fewer than min_neighbors neighbours);
// - the mixed-pixel (edge) fraction: points of a ring whose range lies between their two ring
//   neighbours' ranges, those differing by more than mixed_pixel_min_gap_m, and more than
//   mixed_pixel_min_offset_m from both (a return floating between a foreground and a background).
//
// CompareScanStatistics sets the simulated numbers beside the real ones: scalars as the ratio
// sim / real, histograms as the total-variation distance 0.5 sum |p_i - q_i| of their bin
// fractions (0: identical, 1: disjoint).
//
// Thread safety: free functions; read their inputs only.

#include <filesystem>
#include <string>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::eval {

/// A histogram of uniform bins over [lo, hi); values outside go into the end bins.
struct Histogram {
  std::string name;   ///< e.g. "range_m".
  std::string label;  ///< Axis label, e.g. "range [m]".
  double lo = 0.0;
  double hi = 1.0;
  std::vector<double> counts;
  double sum = 0.0;     ///< Of the values added (for the mean).
  double weight = 0.0;  ///< Total weight added.

  Histogram() = default;
  Histogram(std::string name, std::string label, double lo, double hi, int bins);
  void Add(double value, double w = 1.0);
  /// Adds another histogram's counts (same bins; InvalidArgument otherwise).
  Status Merge(const Histogram& other);
  double BinWidth() const { return (hi - lo) / static_cast<double>(counts.size()); }
  double BinCenter(size_t i) const { return lo + (static_cast<double>(i) + 0.5) * BinWidth(); }
  /// Bin fractions (all 0 when empty).
  std::vector<double> Fractions() const;
  double Mean() const { return weight > 0.0 ? sum / weight : 0.0; }
};

struct ScanStatisticsOptions {
  int num_beams = 64;              ///< Rings expected (HDL-64E: 64).
  int range_image_columns = 1024;  ///< Azimuth cells of the range image.
  double max_range_m = 120.0;      ///< Range histogram span [m].
  double neighborhood_radius_m = 0.5;
  int min_neighbors = 5;  ///< Query point included.
  int query_stride = 16;  ///< Every n-th point is a PCA query.
  double planar_max_variation = 0.02;
  double scatter_min_variation = 0.08;
  double min_planar_extent = 0.05;  ///< l1 / l2 below this: a line (one ring), not a surface.
  double ground_max_z_m = -1.0;     ///< Ground lies below this height in the lidar frame [m].
  double mixed_pixel_min_gap_m = 1.0;
  double mixed_pixel_min_offset_m = 0.2;

  [[nodiscard]] Status Validate()
      const;  ///< InvalidArgument naming "ScanStatisticsOptions::<field>".
};

/// Statistics of one scan or, summed, of a drive.
struct ScanStatistics {
  size_t scans = 0;
  size_t points = 0;                 ///< Finite points.
  size_t rings_recovered_scans = 0;  ///< Scans whose rings were recovered.
  size_t range_image_cells = 0;      ///< Of the scans with rings.
  size_t range_image_filled = 0;
  size_t pca_queries = 0;
  size_t class_ground = 0, class_facade = 0, class_scatter = 0, class_other = 0;
  size_t mixed_pixels = 0;
  size_t mixed_pixel_candidates = 0;  ///< Points with two ring neighbours.
  Histogram range_m, intensity, ring_share, log10_l0, normal_abs_z;

  double PointsPerScan() const { return scans ? static_cast<double>(points) / scans : 0.0; }
  double RangeImageFill() const {
    return range_image_cells ? static_cast<double>(range_image_filled) / range_image_cells : 0.0;
  }
  double ClassShare(size_t count) const {
    return pca_queries ? static_cast<double>(count) / pca_queries : 0.0;
  }
  double MixedPixelFraction() const {
    return mixed_pixel_candidates ? static_cast<double>(mixed_pixels) / mixed_pixel_candidates
                                  : 0.0;
  }
  /// The histograms, in a fixed order.
  std::vector<const Histogram*> Histograms() const {
    return {&range_m, &intensity, &ring_share, &log10_l0, &normal_abs_z};
  }
  /// Sums another drive's or scan's statistics (same options).
  Status Add(const ScanStatistics& other);
};

/// Empty statistics with the histogram bins of `options`.
ScanStatistics MakeScanStatistics(const ScanStatisticsOptions& options);

/// Ring index of every point from the point order (see the header comment), or an empty vector
/// where the scan does not split into num_beams +- 2 rings.
std::vector<int> RecoverRings(const PointCloud& scan, int num_beams);

/// Statistics of one raw scan (points in the lidar frame). InvalidArgument for bad options.
[[nodiscard]] StatusOr<ScanStatistics> ComputeScanStatistics(
    const PointCloud& scan, const ScanStatisticsOptions& options = ScanStatisticsOptions());

/// One number, real beside simulated.
struct StatisticComparison {
  std::string name;
  double real = 0.0;
  double sim = 0.0;
  /// Scalars: sim / real (1 = equal; 0 when real is 0); histograms: the total-variation distance.
  double value = 0.0;
  bool is_histogram = false;
  bool met = false;  ///< Scalars: |ratio - 1| <= tolerance; histograms: distance <= tolerance.
};

/// Scalars (points per scan, range-image fill, the four class shares, the mixed-pixel fraction)
/// and histograms (their means in real/sim), each against `tolerance` (issue 16: 0.2).
std::vector<StatisticComparison> CompareScanStatistics(const ScanStatistics& real,
                                                       const ScanStatistics& sim,
                                                       double tolerance = 0.2);

/// The histograms of `real` and `sim` as small multiples (bin fractions as step lines, real
/// blue, simulated orange, the distance in each title), one PNG.
[[nodiscard]] Status PlotScanStatistics(const ScanStatistics& real, const ScanStatistics& sim,
                                        const std::string& real_label, const std::string& sim_label,
                                        const std::filesystem::path& png_file);

}  // namespace slam_mms::eval
