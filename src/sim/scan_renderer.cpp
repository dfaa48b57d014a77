// ScanRenderer: OpenCV pictures of scans and scenes.
#include "slam_mms/sim/scan_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "io/png_file.hpp"

namespace slam_mms::sim {
namespace {

cv::Vec3b Jet(double x) {  // x in [0, 1], OpenCV's TURBO colour map through a cached table
  static const cv::Mat3b lut = [] {
    cv::Mat1b v(1, 256);
    for (int i = 0; i < 256; ++i) v(0, i) = static_cast<uchar>(i);
    cv::Mat3b c;
    cv::applyColorMap(v, c, cv::COLORMAP_TURBO);
    return c;
  }();
  return lut(0, static_cast<int>(std::clamp(x, 0.0, 1.0) * 255.0));
}

cv::Mat3b TopView(const PointCloud& cloud, int size_px, double half_extent_m) {
  cv::Mat3b img(size_px, size_px, cv::Vec3b(20, 20, 20));
  cv::Mat1f zbuf(size_px, size_px, -1e9f);
  const double scale = size_px / (2.0 * half_extent_m);
  for (const auto& p : cloud.points()) {
    const int u =
        static_cast<int>((half_extent_m - p.y()) * scale);  // x forward = up, y left = left
    const int v = static_cast<int>((half_extent_m - p.x()) * scale);
    if (u < 0 || v < 0 || u >= size_px || v >= size_px) continue;
    if (p.z() > zbuf(v, u)) {
      zbuf(v, u) = p.z();
      img(v, u) = Jet((p.z() + 2.0) / 8.0);
    }
  }
  cv::circle(img, cv::Point(size_px / 2, size_px / 2), 4, cv::Scalar(255, 255, 255), -1);
  return img;
}

cv::Mat3b RangeImage(const PointCloud& cloud, int rows, int cols) {
  cv::Mat3b img(rows, cols, cv::Vec3b(0, 0, 0));
  for (const auto& p : cloud.points()) {
    const double r = p.norm();
    if (r < 0.5) continue;
    const double el = std::asin(p.z() / r) * 180.0 / M_PI;
    const double az = std::atan2(p.y(), p.x());
    const int row = static_cast<int>(std::lround((2.0 - el) / 26.8 * (rows - 1)));
    const int col = static_cast<int>(std::lround(0.5 * (-az / M_PI + 1.0) * cols)) % cols;
    if (row < 0 || row >= rows || col < 0 || col >= cols) continue;
    img(row, col) = Jet(std::min(r, 60.0) / 60.0);
  }
  return img;
}

cv::Mat3b Perspective(const PointCloud& cloud, int w, int h) {
  cv::Mat3b img(h, w, cv::Vec3b(20, 20, 20));
  cv::Mat1f zbuf(h, w, 1e9f);
  // Camera 14 m behind and 7 m above the sensor, looking forward and 20 deg down.
  const Eigen::Vector3d cam(-14.0, 0.0, 7.0);
  const double pitch = 20.0 * M_PI / 180.0, f = 0.9 * w;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.points()[i].cast<double>() - cam;
    // Camera axes: forward (cos, 0, -sin), right (0, -1, 0), down.
    const double zc = p.x() * std::cos(pitch) - p.z() * std::sin(pitch);
    if (zc < 1.0) continue;
    const double xc = -p.y();
    const double yc = -(p.x() * std::sin(pitch) + p.z() * std::cos(pitch));
    const int u = static_cast<int>(w / 2 + f * xc / zc), v = static_cast<int>(h / 2 + f * yc / zc);
    if (u < 0 || v < 0 || u >= w || v >= h || zc >= zbuf(v, u)) continue;
    zbuf(v, u) = static_cast<float>(zc);
    const double inten = cloud.intensities().empty() ? 0.5 : cloud.intensities()[i];
    const cv::Vec3b c = Jet((cloud.points()[i].z() + 2.0) / 8.0);
    const double k = 0.55 + 0.45 * std::min(1.0, inten * 2.0);
    img(v, u) = cv::Vec3b(static_cast<uchar>(c[0] * k), static_cast<uchar>(c[1] * k),
                          static_cast<uchar>(c[2] * k));
  }
  return img;
}

void Label(cv::Mat& img, const std::string& text, cv::Point at) {
  cv::putText(img, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.8, cv::Scalar(0, 0, 0), 4, cv::LINE_AA);
  cv::putText(img, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.8, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);
}

Status Write(const cv::Mat& img, const std::filesystem::path& png) {
  try {
    if (!png.parent_path().empty()) std::filesystem::create_directories(png.parent_path());
  } catch (const std::exception& e) {
    return InternalError("cannot write " + png.string() + ": " + e.what());
  }
  return io_internal::WritePng(png, img.ptr<uint8_t>(0), img.cols, img.rows, img.channels(),
                               img.step[0]);
}

cv::Vec3b ClassColor(SurfaceClass c) {  // BGR
  switch (c) {
    case SurfaceClass::kRoad: return {70, 70, 70};
    case SurfaceClass::kMarking: return {230, 230, 230};
    case SurfaceClass::kCurb: return {170, 170, 170};
    case SurfaceClass::kSidewalk: return {140, 150, 160};
    case SurfaceClass::kTerrain: return {90, 130, 110};
    case SurfaceClass::kBuilding: return {90, 120, 200};
    case SurfaceClass::kPole: return {0, 220, 255};
    case SurfaceClass::kTrunk: return {30, 70, 110};
    case SurfaceClass::kFoliage: return {40, 160, 40};
    case SurfaceClass::kCar: return {200, 80, 60};
    case SurfaceClass::kFence: return {60, 60, 150};
    case SurfaceClass::kOther: return {255, 0, 255};
  }
  return {255, 0, 255};
}

}  // namespace

Status ScanRenderer::WriteScanComparison(const std::vector<LabeledScan>& scans,
                                         const std::filesystem::path& png) {
  if (scans.empty()) return InvalidArgumentError("ScanRenderer::WriteScanComparison: no scans");
  const int top = 760, range_cols = 2083, range_rows = 64, range_scale = 3;
  std::vector<cv::Mat> columns;
  for (const auto& s : scans) {
    if (s.cloud == nullptr)
      return InvalidArgumentError("ScanRenderer: null cloud for '" + s.label + "'");
    cv::Mat tv = TopView(*s.cloud, top, 40.0);
    Label(tv, s.label, {10, 28});
    Label(tv, "top view 80 x 80 m, colour = height", {10, 56});
    cv::Mat ri;
    cv::resize(RangeImage(*s.cloud, range_rows, range_cols), ri,
               cv::Size(top, range_rows * range_scale), 0, 0, cv::INTER_NEAREST);
    // The front of the range image (azimuth about +65..-65 deg) at full resolution.
    const cv::Mat full = RangeImage(*s.cloud, range_rows, range_cols);
    cv::Mat range_band;
    cv::resize(full(cv::Rect(range_cols / 2 - top / 2, 0, top, range_rows)), range_band,
               cv::Size(top, range_rows * range_scale), 0, 0, cv::INTER_NEAREST);
    Label(ri, "range image, 360 deg (colour = range 0-60 m)", {10, 24});
    Label(range_band, "range image, front 130 deg, full resolution", {10, 24});
    cv::Mat pv = Perspective(*s.cloud, top, 480);
    Label(pv, "perspective from behind the car", {10, 28});
    cv::Mat col;
    cv::vconcat(std::vector<cv::Mat>{tv, ri, range_band, pv}, col);
    columns.push_back(col);
  }
  cv::Mat out;
  cv::hconcat(columns, out);
  return Write(out, png);
}

Status ScanRenderer::WriteSceneMap(const CityWorld& world, const ReferenceTrajectory& trajectory,
                                   double t_begin_s, double t_end_s, double mpp,
                                   const std::filesystem::path& png) {
  if (!(mpp > 0.0))
    return InvalidArgumentError("ScanRenderer::WriteSceneMap: meters_per_pixel must be > 0");
  std::vector<Eigen::Vector2d> path;
  Eigen::Vector2d lo(1e18, 1e18), hi(-1e18, -1e18);
  for (double t = t_begin_s; t <= t_end_s; t += 0.1) {
    const Eigen::Vector2d p = trajectory.Pose(t).translation().head<2>();
    path.push_back(p);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (path.empty()) return InvalidArgumentError("ScanRenderer::WriteSceneMap: empty time span");
  lo -= Eigen::Vector2d::Constant(60.0);
  hi += Eigen::Vector2d::Constant(60.0);
  const int w = static_cast<int>((hi.x() - lo.x()) / mpp),
            h = static_cast<int>((hi.y() - lo.y()) / mpp);
  if (w <= 0 || h <= 0 || static_cast<double>(w) * h > 6e7)
    return InvalidArgumentError(
        "ScanRenderer::WriteSceneMap: image too large; raise meters_per_pixel");
  cv::Mat3b img(h, w, cv::Vec3b(25, 25, 25));
  const TriangleMesh& m = world.mesh();
  auto px = [&](const Eigen::Vector3f& v) {
    return cv::Point(static_cast<int>((v.x() - lo.x()) / mpp),
                     static_cast<int>((hi.y() - v.y()) / mpp));
  };
  // Painter's order: by the triangle's highest point.
  std::vector<int> order(m.triangles.size());
  std::iota(order.begin(), order.end(), 0);
  std::vector<float> top(m.triangles.size());
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    const auto& t = m.triangles[i];
    top[i] = std::max({m.vertices[t(0)].z(), m.vertices[t(1)].z(), m.vertices[t(2)].z()});
    if (m.classes[i] == SurfaceClass::kRoad || m.classes[i] == SurfaceClass::kSidewalk ||
        m.classes[i] == SurfaceClass::kTerrain || m.classes[i] == SurfaceClass::kCurb)
      top[i] -= 1000.f;  // ground first
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return top[a] < top[b]; });
  const double ground = world.GroundHeight(path.front().x(), path.front().y());
  for (int i : order) {
    const auto& t = m.triangles[i];
    const cv::Point pts[3] = {px(m.vertices[t(0)]), px(m.vertices[t(1)]), px(m.vertices[t(2)])};
    cv::Vec3b c = ClassColor(m.classes[i]);
    if (m.classes[i] == SurfaceClass::kBuilding) {
      const double k = std::clamp(0.45 + (top[i] - ground) / 40.0, 0.45, 1.3);
      c = cv::Vec3b(cv::saturate_cast<uchar>(c[0] * k), cv::saturate_cast<uchar>(c[1] * k),
                    cv::saturate_cast<uchar>(c[2] * k));
    }
    cv::fillConvexPoly(img, pts, 3, cv::Scalar(c[0], c[1], c[2]), cv::LINE_8);
  }
  for (size_t i = 1; i < path.size(); ++i) {
    const cv::Point a((path[i - 1].x() - lo.x()) / mpp, (hi.y() - path[i - 1].y()) / mpp);
    const cv::Point b((path[i].x() - lo.x()) / mpp, (hi.y() - path[i].y()) / mpp);
    cv::line(img, a, b, cv::Scalar(0, 0, 255), std::max(1, static_cast<int>(0.6 / mpp)),
             cv::LINE_AA);
  }
  cv::Mat out = img;
  Label(out, "procedural city (top view, buildings brighter = taller), red = driven path",
        {12, 30});
  return Write(out, png);
}

}  // namespace slam_mms::sim
