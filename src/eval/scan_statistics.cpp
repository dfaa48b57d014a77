#include "slam_mms/eval/scan_statistics.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "core/option_error.hpp"
#include "eval/plot_canvas.hpp"
#include "eval/points_kdtree.hpp"

namespace slam_mms::eval {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;

using internal::KdTree;
using internal::MomentAccumulator;
using internal::PointsAdaptor;

double WrapPi(double a) {
  while (a > M_PI) a -= kTwoPi;
  while (a <= -M_PI) a += kTwoPi;
  return a;
}

bool Finite(const Eigen::Vector3f& p) { return p.allFinite(); }

}  // namespace

Histogram::Histogram(std::string name_in, std::string label_in, double lo_in, double hi_in,
                     int bins)
    : name(std::move(name_in)),
      label(std::move(label_in)),
      lo(lo_in),
      hi(hi_in),
      counts(static_cast<size_t>(std::max(bins, 1)), 0.0) {}

void Histogram::Add(double value, double w) {
  if (!std::isfinite(value) || counts.empty()) return;
  const double u = (value - lo) / (hi - lo) * static_cast<double>(counts.size());
  const long i =
      std::clamp(static_cast<long>(std::floor(u)), 0L, static_cast<long>(counts.size()) - 1);
  counts[static_cast<size_t>(i)] += w;
  sum += value * w;
  weight += w;
}

Status Histogram::Merge(const Histogram& other) {
  if (other.counts.size() != counts.size() || other.lo != lo || other.hi != hi) {
    return InvalidArgumentError("Histogram::Merge: " + other.name + " has other bins than " + name);
  }
  for (size_t i = 0; i < counts.size(); ++i) counts[i] += other.counts[i];
  sum += other.sum;
  weight += other.weight;
  return OkStatus();
}

std::vector<double> Histogram::Fractions() const {
  double total = 0.0;
  for (double c : counts) total += c;
  std::vector<double> f(counts.size(), 0.0);
  if (total <= 0.0) return f;
  for (size_t i = 0; i < counts.size(); ++i) f[i] = counts[i] / total;
  return f;
}

Status ScanStatisticsOptions::Validate() const {
  constexpr std::string_view kOwner = "ScanStatisticsOptions";
  if (num_beams < 1 || num_beams > 256) {
    return slam_mms::internal::OptionError(kOwner, "num_beams", num_beams, "must be in [1, 256]");
  }
  if (range_image_columns < 16 || range_image_columns > 16384) {
    return slam_mms::internal::OptionError(kOwner, "range_image_columns", range_image_columns,
                                           "must be in [16, 16384]");
  }
  if (!(max_range_m > 0.0) || !std::isfinite(max_range_m)) {
    return slam_mms::internal::OptionError(kOwner, "max_range_m", max_range_m,
                                           "must be finite and > 0");
  }
  if (!(neighborhood_radius_m > 0.0) || !std::isfinite(neighborhood_radius_m)) {
    return slam_mms::internal::OptionError(kOwner, "neighborhood_radius_m", neighborhood_radius_m,
                                           "must be finite and > 0");
  }
  if (min_neighbors < 4) {
    return slam_mms::internal::OptionError(kOwner, "min_neighbors", min_neighbors, "must be >= 4");
  }
  if (query_stride < 1) {
    return slam_mms::internal::OptionError(kOwner, "query_stride", query_stride, "must be >= 1");
  }
  const std::pair<const char*, double> fractions[] = {
      {"planar_max_variation", planar_max_variation},
      {"scatter_min_variation", scatter_min_variation},
      {"min_planar_extent", min_planar_extent}};
  for (const auto& [field, v] : fractions) {
    if (!(v > 0.0) || !(v < 1.0)) {
      return slam_mms::internal::OptionError(kOwner, field, v, "must be in (0, 1)");
    }
  }
  if (!(scatter_min_variation > planar_max_variation)) {
    return slam_mms::internal::OptionError(kOwner, "scatter_min_variation", scatter_min_variation,
                                           "must be > planar_max_variation");
  }
  if (!std::isfinite(ground_max_z_m)) {
    return slam_mms::internal::OptionError(kOwner, "ground_max_z_m", ground_max_z_m,
                                           "must be finite");
  }
  if (!(mixed_pixel_min_gap_m > 0.0) || !std::isfinite(mixed_pixel_min_gap_m)) {
    return slam_mms::internal::OptionError(kOwner, "mixed_pixel_min_gap_m", mixed_pixel_min_gap_m,
                                           "must be finite and > 0");
  }
  if (!(mixed_pixel_min_offset_m > 0.0) ||
      !(mixed_pixel_min_offset_m < 0.5 * mixed_pixel_min_gap_m)) {
    return slam_mms::internal::OptionError(kOwner, "mixed_pixel_min_offset_m",
                                           mixed_pixel_min_offset_m,
                                           "must be in (0, mixed_pixel_min_gap_m / 2)");
  }
  return OkStatus();
}

ScanStatistics MakeScanStatistics(const ScanStatisticsOptions& options) {
  ScanStatistics s;
  const int range_bins = std::max(1, static_cast<int>(std::ceil(options.max_range_m / 2.0)));
  s.range_m = Histogram("range_m", "range [m]", 0.0, 2.0 * range_bins, range_bins);
  s.intensity = Histogram("intensity", "intensity", 0.0, 1.0, 20);
  s.ring_share = Histogram("ring_share", "ring (0 = first in the file)", 0.0, options.num_beams,
                           options.num_beams);
  s.log10_l0 = Histogram("log10_l0", "log10 smallest eigenvalue [m^2], r = 0.5 m", -7.0, -1.0, 30);
  s.normal_abs_z = Histogram("normal_abs_z", "|normal z|", 0.0, 1.0, 20);
  return s;
}

Status ScanStatistics::Add(const ScanStatistics& o) {
  scans += o.scans;
  points += o.points;
  rings_recovered_scans += o.rings_recovered_scans;
  range_image_cells += o.range_image_cells;
  range_image_filled += o.range_image_filled;
  pca_queries += o.pca_queries;
  class_ground += o.class_ground;
  class_facade += o.class_facade;
  class_scatter += o.class_scatter;
  class_other += o.class_other;
  mixed_pixels += o.mixed_pixels;
  mixed_pixel_candidates += o.mixed_pixel_candidates;
  SLAM_MMS_RETURN_IF_ERROR(range_m.Merge(o.range_m));
  SLAM_MMS_RETURN_IF_ERROR(intensity.Merge(o.intensity));
  SLAM_MMS_RETURN_IF_ERROR(ring_share.Merge(o.ring_share));
  SLAM_MMS_RETURN_IF_ERROR(log10_l0.Merge(o.log10_l0));
  return normal_abs_z.Merge(o.normal_abs_z);
}

namespace {

// Azimuth atan2(y, x) of every point; NaN where the point is not finite or on the z axis.
std::vector<double> Azimuths(const std::vector<Eigen::Vector3f>& pts) {
  std::vector<double> az(pts.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t i = 0; i < pts.size(); ++i) {
    if (!Finite(pts[i]) || (pts[i].x() == 0.0f && pts[i].y() == 0.0f)) continue;
    az[i] = std::atan2(static_cast<double>(pts[i].y()), static_cast<double>(pts[i].x()));
  }
  return az;
}

// RecoverRings on the points' azimuths (NaN: no ring).
std::vector<int> RingsFromAzimuth(const std::vector<double>& az_all, int num_beams) {
  std::vector<double> az;
  std::vector<size_t> idx;
  az.reserve(az_all.size());
  idx.reserve(az_all.size());
  for (size_t i = 0; i < az_all.size(); ++i) {
    if (std::isnan(az_all[i])) continue;
    az.push_back(az_all[i]);
    idx.push_back(i);
  }
  if (az.size() < static_cast<size_t>(10 * num_beams)) return {};
  // Rotation direction: the sign of the median azimuth step.
  std::vector<double> steps(az.size() - 1);
  for (size_t i = 1; i < az.size(); ++i) steps[i - 1] = WrapPi(az[i] - az[i - 1]);
  std::vector<double> sorted = steps;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double dir = sorted[sorted.size() / 2] >= 0.0 ? 1.0 : -1.0;
  // Progress along the rotation, unwrapped: steps are positive within a ring; a step backwards
  // by more than 0.5 rad is a gap of more than half a turn (no returns), not a step back. Ring k
  // starts when the progress passes 2 pi k (a small margin for ring starts that jitter by a few
  // firings).
  constexpr double kMargin = 0.05;
  std::vector<int> ring(az_all.size(), -1);
  double progress = 0.0;
  ring[idx[0]] = 0;
  int max_ring = 0;
  for (size_t i = 1; i < az.size(); ++i) {
    double d = dir * steps[i - 1];
    if (d < -0.5) d += kTwoPi;
    progress += std::max(d, 0.0);
    const int r = static_cast<int>(std::floor((progress + kMargin) / kTwoPi));
    ring[idx[i]] = r;
    max_ring = std::max(max_ring, r);
  }
  const int rings = max_ring + 1;
  if (std::abs(rings - num_beams) > 2) return {};
  return ring;
}

}  // namespace

std::vector<int> RecoverRings(const PointCloud& scan, int num_beams) {
  return RingsFromAzimuth(Azimuths(scan.points()), num_beams);
}

StatusOr<ScanStatistics> ComputeScanStatistics(const PointCloud& scan,
                                               const ScanStatisticsOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  ScanStatistics s = MakeScanStatistics(options);
  s.scans = 1;
  const std::vector<Eigen::Vector3f>& pts = scan.points();
  const std::vector<float>& inten = scan.intensities();
  std::vector<Eigen::Vector3f> finite;
  finite.reserve(pts.size());
  std::vector<double> range(pts.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t i = 0; i < pts.size(); ++i) {
    if (!Finite(pts[i])) continue;
    finite.push_back(pts[i]);
    range[i] = pts[i].norm();
    s.range_m.Add(range[i]);
    if (i < inten.size()) s.intensity.Add(inten[i]);
  }
  s.points = finite.size();

  // Rings: share per ring, range-image fill, mixed pixels along each ring.
  const std::vector<double> az = Azimuths(pts);
  const std::vector<int> ring = RingsFromAzimuth(az, options.num_beams);
  if (!ring.empty()) {
    s.rings_recovered_scans = 1;
    int rings = 0;
    for (int r : ring) rings = std::max(rings, r + 1);
    const int cols = options.range_image_columns;
    std::vector<uint8_t> cell(static_cast<size_t>(rings) * cols, 0);
    std::vector<std::vector<size_t>> members(static_cast<size_t>(rings));
    for (size_t i = 0; i < pts.size(); ++i) {
      if (ring[i] < 0) continue;
      s.ring_share.Add(ring[i]);
      const int c = std::clamp(static_cast<int>((az[i] + M_PI) / kTwoPi * cols), 0, cols - 1);
      cell[static_cast<size_t>(ring[i]) * cols + c] = 1;
      members[static_cast<size_t>(ring[i])].push_back(i);
    }
    s.range_image_cells = cell.size();
    for (uint8_t c : cell) s.range_image_filled += c;
    // Neighbours on a ring: consecutive points at most ~3 firings of an HDL-64E apart.
    constexpr double kMaxNeighbourStep = 0.01;  // rad
    // A mixed pixel is isolated: its outer neighbours continue the foreground and background
    // surfaces (range steps below mixed_pixel_min_offset_m) while it lies between them. A steep
    // but smooth surface (a wall at grazing incidence) has large steps all along and is not one.
    const double tol = options.mixed_pixel_min_offset_m;
    for (const std::vector<size_t>& m : members) {
      // close[j]: points j and j + 1 of the ring are neighbours.
      std::vector<uint8_t> close(m.size(), 0);
      for (size_t j = 0; j + 1 < m.size(); ++j) {
        close[j] = std::abs(WrapPi(az[m[j + 1]] - az[m[j]])) <= kMaxNeighbourStep;
      }
      for (size_t k = 2; k + 2 < m.size(); ++k) {
        if (!(close[k - 2] && close[k - 1] && close[k] && close[k + 1])) continue;
        ++s.mixed_pixel_candidates;
        const double r0 = range[m[k - 2]], ra = range[m[k - 1]], rb = range[m[k]],
                     rc = range[m[k + 1]], r4 = range[m[k + 2]];
        const double near = std::min(ra, rc), far = std::max(ra, rc);
        if (far - near > options.mixed_pixel_min_gap_m && std::abs(r0 - ra) < tol &&
            std::abs(r4 - rc) < tol && rb > near + tol && rb < far - tol) {
          ++s.mixed_pixels;
        }
      }
    }
  }

  // Local geometry.
  if (finite.size() >= static_cast<size_t>(options.min_neighbors)) {
    const PointsAdaptor adaptor{finite};
    KdTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    tree.buildIndex();
    const float r2 =
        static_cast<float>(options.neighborhood_radius_m * options.neighborhood_radius_m);
    const nanoflann::SearchParams params(32, 0.0f, /*sorted=*/false);
    for (size_t q = 0; q < finite.size(); q += static_cast<size_t>(options.query_stride)) {
      ++s.pca_queries;
      MomentAccumulator acc(r2, finite[q], finite);
      tree.radiusSearchCustomCallback(finite[q].data(), acc, params);
      if (acc.size() < static_cast<size_t>(options.min_neighbors)) {
        ++s.class_other;
        continue;
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(acc.Covariance());
      const Eigen::Vector3d l = eig.eigenvalues().cwiseMax(0.0);  // ascending
      const double total = l.sum();
      if (!(total > 0.0)) {
        ++s.class_other;
        continue;
      }
      s.log10_l0.Add(std::log10(std::max(l[0], 1e-12)));
      const double variation = l[0] / total;
      const bool surface = l[1] >= options.min_planar_extent * l[2];
      const double nz = std::abs(eig.eigenvectors().col(0).z());
      if (surface) s.normal_abs_z.Add(nz);
      if (surface && variation < options.planar_max_variation && nz > 0.9 &&
          finite[q].z() < options.ground_max_z_m) {
        ++s.class_ground;
      } else if (surface && variation < options.planar_max_variation && nz < 0.3) {
        ++s.class_facade;
      } else if (variation > options.scatter_min_variation) {
        ++s.class_scatter;
      } else {
        ++s.class_other;
      }
    }
  }
  return s;
}

std::vector<StatisticComparison> CompareScanStatistics(const ScanStatistics& real,
                                                       const ScanStatistics& sim,
                                                       double tolerance) {
  std::vector<StatisticComparison> out;
  auto scalar = [&](const std::string& name, double r, double s) {
    StatisticComparison c;
    c.name = name;
    c.real = r;
    c.sim = s;
    c.value = r != 0.0 ? s / r : 0.0;
    c.met = r != 0.0 && std::abs(c.value - 1.0) <= tolerance;
    out.push_back(c);
  };
  scalar("points_per_scan", real.PointsPerScan(), sim.PointsPerScan());
  scalar("range_image_fill", real.RangeImageFill(), sim.RangeImageFill());
  scalar("share_ground", real.ClassShare(real.class_ground), sim.ClassShare(sim.class_ground));
  scalar("share_facade", real.ClassShare(real.class_facade), sim.ClassShare(sim.class_facade));
  scalar("share_scatter", real.ClassShare(real.class_scatter), sim.ClassShare(sim.class_scatter));
  scalar("share_other", real.ClassShare(real.class_other), sim.ClassShare(sim.class_other));
  scalar("mixed_pixel_fraction", real.MixedPixelFraction(), sim.MixedPixelFraction());
  const std::vector<const Histogram*> hr = real.Histograms(), hs = sim.Histograms();
  for (size_t k = 0; k < hr.size(); ++k) {
    StatisticComparison c;
    c.name = hr[k]->name;
    c.is_histogram = true;
    c.real = hr[k]->Mean();
    c.sim = hs[k]->Mean();
    const std::vector<double> p = hr[k]->Fractions(), q = hs[k]->Fractions();
    double tv = 0.0;
    for (size_t i = 0; i < p.size() && i < q.size(); ++i) tv += std::abs(p[i] - q[i]);
    c.value = 0.5 * tv;
    c.met = hr[k]->weight > 0.0 && hs[k]->weight > 0.0 && c.value <= tolerance;
    out.push_back(c);
  }
  return out;
}

Status PlotScanStatistics(const ScanStatistics& real, const ScanStatistics& sim,
                          const std::string& real_label, const std::string& sim_label,
                          const std::filesystem::path& png_file) {
  const std::vector<const Histogram*> hr = real.Histograms(), hs = sim.Histograms();
  constexpr int kW = 620, kH = 380, kCols = 2;
  const int rows = static_cast<int>((hr.size() + kCols - 1) / kCols);
  cv::Mat figure(rows * kH, kCols * kW, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar real_color = internal::PaletteColor(0), sim_color = internal::PaletteColor(1);
  for (size_t k = 0; k < hr.size(); ++k) {
    internal::PlotCanvas canvas(kW, kH, 20, 48, 70);
    const std::vector<double> p = hr[k]->Fractions(), q = hs[k]->Fractions();
    double y_hi = 0.0, tv = 0.0;
    for (size_t i = 0; i < p.size(); ++i) {
      y_hi = std::max({y_hi, p[i], q[i]});
      tv += std::abs(p[i] - q[i]);
    }
    canvas.SetRange(hr[k]->lo, hr[k]->hi, 0.0, std::max(1e-3, 1.08 * y_hi), false);
    canvas.DrawGrid();
    for (int which = 0; which < 2; ++which) {
      const std::vector<double>& f = which == 0 ? p : q;
      std::vector<cv::Point2d> line;
      for (size_t i = 0; i < f.size(); ++i) {
        const double x0 = hr[k]->lo + static_cast<double>(i) * hr[k]->BinWidth();
        line.emplace_back(x0, f[i]);
        line.emplace_back(x0 + hr[k]->BinWidth(), f[i]);
      }
      canvas.Polyline(line, which == 0 ? real_color : sim_color, 2);
    }
    char title[160];
    std::snprintf(title, sizeof(title), "%s: distance %.3f", hr[k]->name.c_str(), 0.5 * tv);
    canvas.DrawAxes(hr[k]->label, "fraction", title);
    canvas.Legend({{real_label, real_color}, {sim_label, sim_color}});
    const int r = static_cast<int>(k) / kCols, c = static_cast<int>(k) % kCols;
    canvas.image().copyTo(figure(cv::Rect(c * kW, r * kH, kW, kH)));
  }
  return internal::SavePng(figure, png_file);
}

}  // namespace slam_mms::eval
