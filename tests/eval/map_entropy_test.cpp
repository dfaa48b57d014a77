#include "slam_mms/eval/map_entropy.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <random>

#include "slam_mms/core/voxel_downsample.hpp"

namespace slam_mms::eval {
namespace {

// A planar disc of radius 0.3 m in the xy plane with Gaussian noise sigma_n along z. In-plane
// samples are a sunflower (Vogel) spiral: uniform over the disc and deterministic, so the in-plane
// covariance is R^2/4 to O(1/N) and only the seeded noise is random.
PointCloud NoisyDisc(int n, double sigma_n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_n);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  PointCloud cloud;
  for (int i = 0; i < n; ++i) {
    const double r = 0.3 * std::sqrt((i + 0.5) / n);
    const double a = golden * i;
    cloud.Add(Eigen::Vector3f(static_cast<float>(r * std::cos(a)),
                              static_cast<float>(r * std::sin(a)), static_cast<float>(noise(rng))));
  }
  return cloud;
}

// Brute-force oracle: O(N^2) neighbours (same float squared distance, same strict < r^2 rule).
MapEntropyResult BruteForceEntropy(const std::vector<Eigen::Vector3f>& pts, double radius,
                                   int min_neighbors) {
  MapEntropyResult r;
  const float r2 = static_cast<float>(radius * radius);
  double sum_h = 0.0, sum_pv = 0.0, sum_nb = 0.0;
  for (const Eigen::Vector3f& q : pts) {
    std::vector<Eigen::Vector3d> nb;
    for (const Eigen::Vector3f& p : pts) {
      const float dx = q.x() - p.x(), dy = q.y() - p.y(), dz = q.z() - p.z();
      const float d2 = dx * dx + dy * dy + dz * dz;
      if (d2 < r2) nb.push_back(p.cast<double>());
    }
    if (static_cast<int>(nb.size()) < min_neighbors) {
      ++r.num_sparse_points;
      continue;
    }
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : nb) mean += p;
    mean /= nb.size();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : nb) cov += (p - mean) * (p - mean).transpose();
    cov /= nb.size();
    const double det = cov.determinant();
    if (!(det > 0.0)) {
      ++r.num_degenerate_points;
      continue;
    }
    sum_h += 0.5 * std::log((2.0 * M_PI * M_E * cov).determinant());
    sum_pv += Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues()(0);
    sum_nb += static_cast<double>(nb.size());
    ++r.num_valid_points;
  }
  r.mean_map_entropy = sum_h / r.num_valid_points;
  r.mean_plane_variance_m2 = sum_pv / r.num_valid_points;
  r.mean_neighbors = sum_nb / r.num_valid_points;
  return r;
}

TEST(MapEntropyTest, NoisyDiscMatchesTheReferenceValues) {
  // SENSORS_AND_METRICS.md: sigma_n 0.005 -> -4.836; 0.01 -> -4.143; 0.02 -> -3.449; 0.05 -> -2.533
  // (det(2 pi e Sigma), Sigma = diag(R^2/4, R^2/4, sigma_n^2)). Every point sees the whole disc
  // (r = 1 m > diameter), no voxel grid.
  MapEntropyOptions o;
  o.radius_m = 1.0;
  o.voxel_size_m = 0.0;
  const std::vector<std::pair<double, double>> cases = {
      {0.005, -4.836}, {0.01, -4.143}, {0.02, -3.449}, {0.05, -2.533}};
  const int n = 6000;
  double previous = 0.0;
  for (size_t k = 0; k < cases.size(); ++k) {
    const auto [sigma, expected] = cases[k];
    const StatusOr<MapEntropyResult> r = ComputeMapEntropy(NoisyDisc(n, sigma, 42 + k), o);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    EXPECT_EQ(r->num_valid_points, static_cast<size_t>(n));
    EXPECT_EQ(r->num_sparse_points, 0u);
    EXPECT_NEAR(r->mean_neighbors, n, 1e-9);
    // Sample noise variance has relative s.d. sqrt(2/N) = 1.8 %: h within ~0.01 (1 s.d.).
    std::printf("noisy disc sigma_n %.3f m: H = %.4f (reference %.3f), plane variance %.3e m^2\n",
                sigma, r->mean_map_entropy, expected, r->mean_plane_variance_m2);
    EXPECT_NEAR(r->mean_map_entropy, expected, 0.03) << "sigma_n = " << sigma;
    // Plane variance: the smallest eigenvalue is the noise variance.
    EXPECT_NEAR(std::sqrt(r->mean_plane_variance_m2), sigma, 0.05 * sigma);
    if (k > 0) {
      // ln(sigma ratio): ln 2 per doubling, ln 2.5 from 0.02 to 0.05.
      EXPECT_NEAR(r->mean_map_entropy - previous, std::log(sigma / cases[k - 1].first), 0.04);
    }
    previous = r->mean_map_entropy;
  }
}

TEST(MapEntropyTest, MatchesBruteForceOracle) {
  // Two noisy planes, a blob and sparse outliers.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 3.0f);
  std::normal_distribution<float> g(0.0f, 0.02f);
  PointCloud cloud;
  for (int i = 0; i < 1500; ++i) cloud.Add({u(rng), u(rng), g(rng)});
  for (int i = 0; i < 1000; ++i) cloud.Add({u(rng), 1.5f + g(rng), u(rng)});
  for (int i = 0; i < 300; ++i)
    cloud.Add({2.0f + 5 * g(rng), 2.0f + 5 * g(rng), 1.0f + 5 * g(rng)});
  for (int i = 0; i < 40; ++i)
    cloud.Add({10.0f + 3 * u(rng), 10.0f + 3 * u(rng), 10.0f + 3 * u(rng)});

  MapEntropyOptions o;
  o.radius_m = 0.3;
  o.voxel_size_m = 0.0;
  o.min_neighbors = 6;
  const StatusOr<MapEntropyResult> r = ComputeMapEntropy(cloud, o);
  ASSERT_TRUE(r.ok());
  const MapEntropyResult bf = BruteForceEntropy(cloud.points(), o.radius_m, o.min_neighbors);
  EXPECT_EQ(r->num_evaluated_points, cloud.size());
  EXPECT_EQ(r->num_valid_points, bf.num_valid_points);
  EXPECT_EQ(r->num_sparse_points, bf.num_sparse_points);
  EXPECT_GE(r->num_sparse_points, 30u);  // the outliers
  EXPECT_EQ(r->num_degenerate_points, 0u);
  EXPECT_NEAR(r->mean_map_entropy, bf.mean_map_entropy, 1e-9);
  EXPECT_NEAR(r->mean_plane_variance_m2, bf.mean_plane_variance_m2, 1e-12);
  EXPECT_EQ(r->mean_neighbors, bf.mean_neighbors);  // the same neighbour sets

  // With the paper's 0.1 m voxel grid: downsample by brute force, then the brute-force entropy.
  o.voxel_size_m = 0.1;
  o.radius_m = 0.5;
  const StatusOr<MapEntropyResult> rv = ComputeMapEntropy(cloud, o);
  ASSERT_TRUE(rv.ok());
  const StatusOr<PointCloud> down = VoxelDownsample(cloud, 0.1);
  ASSERT_TRUE(down.ok());
  const MapEntropyResult bfv = BruteForceEntropy(down->points(), 0.5, o.min_neighbors);
  EXPECT_EQ(rv->num_input_points, cloud.size());
  EXPECT_EQ(rv->num_evaluated_points, down->size());
  EXPECT_LT(rv->num_evaluated_points, cloud.size());
  EXPECT_EQ(rv->num_valid_points, bfv.num_valid_points);
  EXPECT_NEAR(rv->mean_map_entropy, bfv.mean_map_entropy, 1e-9);
}

TEST(MapEntropyTest, ThreadCountDoesNotChangeTheResult) {
  const PointCloud cloud = NoisyDisc(20000, 0.01, 5);
  MapEntropyOptions o;
  o.radius_m = 0.05;
  o.voxel_size_m = 0.0;
  o.num_threads = 1;
  const StatusOr<MapEntropyResult> a = ComputeMapEntropy(cloud, o);
  o.num_threads = 3;
  const StatusOr<MapEntropyResult> b = ComputeMapEntropy(cloud, o);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->mean_map_entropy, b->mean_map_entropy);  // bitwise: chunk-ordered sums
  EXPECT_EQ(a->num_valid_points, b->num_valid_points);
}

// The cell grid covers at most 2^21 cells of edge r per axis; a cloud wider than that is
// searched with the k-d tree: both give the same neighbourhoods.
TEST(MapEntropyTest, GridAndKdTreeSearchesAgree) {
  const PointCloud near = NoisyDisc(20000, 0.01, 5);
  MapEntropyOptions o;
  o.radius_m = 0.05;
  o.voxel_size_m = 0.0;
  PointCloud wide = near;
  wide.Add({150000.0f, 0.0f, 0.0f});  // 150 km away: 3e6 cells of 5 cm
  const StatusOr<MapEntropyResult> grid = ComputeMapEntropy(near, o);
  const StatusOr<MapEntropyResult> tree = ComputeMapEntropy(wide, o);
  ASSERT_TRUE(grid.ok() && tree.ok());
  ASSERT_GT(grid->num_valid_points, 10000u);
  EXPECT_EQ(tree->num_valid_points, grid->num_valid_points);
  EXPECT_EQ(tree->num_sparse_points, grid->num_sparse_points + 1);  // the far point
  EXPECT_EQ(tree->num_degenerate_points, grid->num_degenerate_points);
  EXPECT_EQ(tree->mean_neighbors, grid->mean_neighbors);
  EXPECT_NEAR(tree->mean_map_entropy, grid->mean_map_entropy, 1e-12);
  EXPECT_NEAR(tree->mean_plane_variance_m2, grid->mean_plane_variance_m2, 1e-15);
}

TEST(MapEntropyTest, SharperMapHasLowerEntropy) {
  // Default options (r = 0.5 m, 0.1 m voxels) on a 4 x 4 m wall sampled every 1 cm.
  auto wall = [](double sigma) {
    std::mt19937 rng(11);
    std::normal_distribution<double> g(0.0, sigma);
    PointCloud c;
    for (int i = 0; i < 400; ++i) {
      for (int j = 0; j < 400; ++j) {
        c.Add(Eigen::Vector3f(0.01f * i, 0.01f * j, static_cast<float>(g(rng))));
      }
    }
    return c;
  };
  const StatusOr<MapEntropyResult> sharp = ComputeMapEntropy(wall(0.01));
  const StatusOr<MapEntropyResult> blurred = ComputeMapEntropy(wall(0.05));
  ASSERT_TRUE(sharp.ok() && blurred.ok());
  // 40 x 40 voxel columns, each split at z = 0 into two layers (|z| < 0.1 m at sigma 1 cm).
  EXPECT_EQ(sharp->num_evaluated_points, 3200u);
  EXPECT_LT(sharp->mean_map_entropy, blurred->mean_map_entropy - 0.5);
  EXPECT_LT(sharp->mean_plane_variance_m2, blurred->mean_plane_variance_m2);
}

TEST(MapEntropyTest, SparseAndDegenerateNeighbourhoodsAreCounted) {
  PointCloud cloud;
  // An exactly planar 10 x 10 grid (z = 0): det(Sigma) = 0 for every point.
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) cloud.Add(Eigen::Vector3f(0.05f * i, 0.05f * j, 0.0f));
  }
  // Three isolated points.
  cloud.Add({50, 0, 0});
  cloud.Add({0, 50, 0});
  cloud.Add({0, 0, 50});
  cloud.Add({std::nanf(""), 0, 0});  // non-finite: ignored
  MapEntropyOptions o;
  o.voxel_size_m = 0.0;
  const StatusOr<MapEntropyResult> r = ComputeMapEntropy(cloud, o);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->num_input_points, 103u);
  EXPECT_EQ(r->num_sparse_points, 3u);
  EXPECT_EQ(r->num_degenerate_points, 100u);
  EXPECT_EQ(r->num_valid_points, 0u);
  EXPECT_TRUE(std::isnan(r->mean_map_entropy));
}

TEST(MapEntropyTest, OptionsValidation) {
  MapEntropyOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.radius_m = 0.0;
  EXPECT_NE(o.Validate().message().find("radius_m"), std::string::npos);
  o = MapEntropyOptions();
  o.min_neighbors = 3;
  EXPECT_NE(o.Validate().message().find("min_neighbors"), std::string::npos);
  o = MapEntropyOptions();
  o.voxel_size_m = -0.1;
  EXPECT_EQ(ComputeMapEntropy(PointCloud(), o).status().code(), StatusCode::kInvalidArgument);
  const StatusOr<MapEntropyResult> empty = ComputeMapEntropy(PointCloud());
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(empty->num_valid_points, 0u);
}

}  // namespace
}  // namespace slam_mms::eval
