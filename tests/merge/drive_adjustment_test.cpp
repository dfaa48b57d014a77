// DriveAdjustment on synthetic drives: street corridors (ground, two facades with seeded
// protrusions, poles) sampled as point clouds; each drive a chain of submaps with reckon factors
// and GNSS fixes, as level 2 would have written them.
#include "slam_mms/merge/drive_adjustment.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace slam_mms {
namespace {

// A street along x at y = y0 with facades at y0 +- half_width; protrusions and poles seeded.
struct Street {
  double y0 = 0.0;
  double half_width = 8.0;
  double x_min = -40.0, x_max = 200.0;
  std::vector<Eigen::Vector3d> points;

  Street(uint32_t seed, double y0_in, double half_width_in) : y0(y0_in), half_width(half_width_in) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double step = 0.4;
    for (double x = x_min; x <= x_max; x += step) {
      for (double y = -half_width; y <= half_width; y += step) points.emplace_back(x, y0 + y, 0.0);
      for (double z = 0.0; z <= 10.0; z += step) {
        points.emplace_back(x, y0 - half_width, z);
        points.emplace_back(x, y0 + half_width, z);
      }
    }
    // Protrusions: boxes of 1-4 m width, 0.3-1.5 m depth, 2-8 m height on both facades.
    for (int side : {-1, 1}) {
      for (double x = x_min + u(rng) * 6.0; x < x_max; x += 3.0 + u(rng) * 8.0) {
        const double w = 1.0 + 3.0 * u(rng), d = 0.3 + 1.2 * u(rng), h = 2.0 + 6.0 * u(rng);
        const double face_y = y0 + side * (half_width - d);
        for (double px = x; px <= x + w; px += step) {
          for (double z = 0.0; z <= h; z += step) points.emplace_back(px, face_y, z);
        }
        for (double dy = 0.0; dy <= d; dy += step) {
          for (double z = 0.0; z <= h; z += step) {
            points.emplace_back(x, face_y + side * dy, z);
            points.emplace_back(x + w, face_y + side * dy, z);
          }
        }
      }
      // Poles 4 m high, 0.15 m radius, 1.5 m from the curb line.
      for (double x = x_min + u(rng) * 10.0; x < x_max; x += 8.0 + u(rng) * 12.0) {
        const double py = y0 + side * (half_width - 2.5);
        for (double z = 0.0; z <= 4.0; z += step) {
          for (int k = 0; k < 8; ++k) {
            const double a = k * M_PI / 4.0;
            points.emplace_back(x + 0.15 * std::cos(a), py + 0.15 * std::sin(a), z);
          }
        }
      }
    }
  }

  // Points within `radius` of `T_world_submap`'s origin, in the submap frame, with noise.
  PointCloud Cloud(const Eigen::Isometry3d& T_world_submap, double radius,
                   std::mt19937* rng) const {
    std::normal_distribution<double> n(0.0, 0.01);
    const Eigen::Isometry3d T_submap_world = T_world_submap.inverse();
    PointCloud c;
    for (const Eigen::Vector3d& p : points) {
      if ((p - T_world_submap.translation()).head<2>().norm() > radius) continue;
      const Eigen::Vector3d q = T_submap_world * p + Eigen::Vector3d(n(*rng), n(*rng), n(*rng));
      c.Add(q.cast<float>(), 0.5f);
    }
    return c;
  }
};

Eigen::Isometry3d Pose(double x, double y, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 1.0);
  return T;
}

// A drive along `street` from x0 to x1 (either direction), a submap every 10 m with two scans;
// its submap poses (and GNSS fixes) offset by `gnss_offset` from the truth; clouds from
// `cloud_street` (a different street for a false overlap).
struct SyntheticDrive {
  DriveResult result;
  std::vector<Eigen::Isometry3d> true_poses;  // per submap
};

SyntheticDrive MakeDrive(const Street& cloud_street, double y, double x0, double x1,
                         const Eigen::Vector3d& gnss_offset, uint32_t seed, bool with_gnss = true,
                         double gnss_noise_m = 0.02) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  SyntheticDrive d;
  d.result.origin = {48.0, 11.0, 500.0};
  const double dir = x1 > x0 ? 1.0 : -1.0;
  const double yaw = dir > 0 ? 0.0 : M_PI;
  const int count = static_cast<int>(std::abs(x1 - x0) / 10.0) + 1;
  const Timestamp t0 = Timestamp::FromSeconds(1.7e9 + seed);
  for (int k = 0; k < count; ++k) {
    const Eigen::Isometry3d T_true = Pose(x0 + dir * 10.0 * k, y, yaw);
    d.true_poses.push_back(T_true);
    DriveSubmap s;
    s.id = k;
    s.start = t0.PlusSeconds(1.0 * k);
    s.end = s.start.PlusSeconds(0.5);
    Eigen::Isometry3d T = T_true;
    T.translation() += gnss_offset;
    s.T_world_submap = T;
    for (int j = 0; j < 2; ++j) {
      SubmapScanPose p;
      p.submap = k;
      p.scan_id = 2 * k + j;
      p.stamp = s.start.PlusSeconds(0.5 * j);
      p.T_submap_scan = Pose(5.0 * j, 0.0, 0.0);
      p.T_submap_scan.translation().z() = 0.0;
      p.T_world_scan = s.T_world_submap * p.T_submap_scan;
      s.scans.push_back(p);
      s.cov_submap_scan.push_back(Matrix6d::Identity() * 1e-4);
    }
    s.registration_cloud = cloud_street.Cloud(T_true, 20.0, &rng);
    s.map_cloud = s.registration_cloud;
    d.result.submaps.push_back(std::move(s));
    if (k > 0) {
      SubmapGraphFactor f;
      f.kind = SubmapFactorKind::kReckon;
      f.a = k - 1;
      f.b = k;
      f.T = d.true_poses[k - 1].inverse() * T_true;
      f.covariance = Matrix6d::Identity() * 1e-4;
      f.covariance.diagonal().tail<3>().setConstant(0.02 * 0.02);
      d.result.factors.push_back(f);
    }
    {
      // Level 2's attitude prior: roll and pitch from gravity, yaw loose, position free.
      SubmapGraphFactor f;
      f.kind = SubmapFactorKind::kPosePrior;
      f.a = f.b = k;
      f.T = T;
      f.covariance = Matrix6d::Zero();
      f.covariance.diagonal() << 1e-4, 1e-4, 1e-2, 1e6, 1e6, 1e6;
      d.result.factors.push_back(f);
    }
    if (with_gnss) {
      SubmapGraphFactor g;
      g.kind = SubmapFactorKind::kGnss;
      g.a = g.b = k;
      g.p_world_antenna = T_true.translation() + gnss_offset +
                          gnss_noise_m * Eigen::Vector3d(n(rng), n(rng), n(rng));
      g.covariance = Matrix6d::Zero();
      g.covariance.topLeftCorner<3, 3>() = 0.03 * 0.03 * Eigen::Matrix3d::Identity();
      d.result.factors.push_back(g);
    }
  }
  return d;
}

double MaxPositionError(const DriveResult& r, const std::vector<Eigen::Isometry3d>& truth,
                        const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
  double e = 0.0;
  for (size_t k = 0; k < r.submaps.size(); ++k) {
    e = std::max(
        e, (r.submaps[k].T_world_submap.translation() - truth[k].translation() - shift).norm());
  }
  return e;
}

TEST(DriveAdjustmentTest, TwoDrivesWithA5mGnssOffsetArePulledTogether) {
  const Street street(1, 0.0, 8.0);
  SyntheticDrive a = MakeDrive(street, -3.0, 0.0, 100.0, Eigen::Vector3d::Zero(), 11);
  const Eigen::Vector3d offset(3.0, 4.0, 0.0);  // 5 m
  SyntheticDrive b = MakeDrive(street, 3.0, 120.0, 20.0, offset, 12);
  DriveAdjustment::Options opt;
  opt.gnss_bias_sigma_m = 10.0;  // the drives' GNSS on two datums
  auto r = DriveAdjustment::Run({{"a", a.result}, {"b", b.result}}, opt);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_TRUE(r->summary.usable());
  int accepted = 0;
  double before = 0.0, after = 0.0;
  for (const auto& ov : r->overlaps) {
    if (!ov.accepted) continue;
    ++accepted;
    before = std::max(before, ov.offset_before_m);
    after = std::max(after, ov.offset_after_m);
  }
  EXPECT_GE(accepted, 5);
  EXPECT_GT(before, 4.5);
  EXPECT_LT(after, 0.03);
  // The relative GNSS bias is the offset; drive b moved rigidly onto drive a (or both halfway).
  const Eigen::Vector3d rel = r->gnss_bias_m[1] - r->gnss_bias_m[0];
  EXPECT_LT((rel - offset).norm(), 0.05) << rel.transpose();
  // Drive a as a whole may move (half the offset where both GNSS count alike): its mean shift.
  Eigen::Vector3d shift_a = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < a.true_poses.size(); ++k) {
    shift_a +=
        r->drives[0].result.submaps[k].T_world_submap.translation() - a.true_poses[k].translation();
  }
  shift_a /= static_cast<double>(a.true_poses.size());
  EXPECT_LT(MaxPositionError(r->drives[0].result, a.true_poses, shift_a), 0.05);
  EXPECT_LT(MaxPositionError(r->drives[1].result, b.true_poses, shift_a), 0.05);
}

// Drive b's fixes scatter 0.3 m but are stated at 0.03 m (as a float stretch taken for fixed):
// merged as stated, b's fixes pull drive a where the two overlap. Variance component estimation
// finds b's GNSS factor near (0.3 / 0.03)^2 = 100 (69 when written) and a keeps its accuracy.
TEST(DriveAdjustmentTest, VarianceComponentsStopAnOverconfidentDriveFromPullingAnother) {
  const Street street(1, 0.0, 8.0);
  SyntheticDrive a = MakeDrive(street, -3.0, 0.0, 100.0, Eigen::Vector3d::Zero(), 21);
  SyntheticDrive b = MakeDrive(street, 3.0, 200.0, 0.0, Eigen::Vector3d::Zero(), 22, true, 0.3);
  // Reckon factors with the noise they state (1 mrad, 2 cm): their variance factor is about 1.
  std::mt19937 rng(23);
  std::normal_distribution<double> n(0.0, 1.0);
  for (SyntheticDrive* d : {&a, &b}) {
    for (SubmapGraphFactor& f : d->result.factors) {
      if (f.kind != SubmapFactorKind::kReckon) continue;
      Vector6d xi;
      for (int k = 0; k < 6; ++k) xi[k] = (k < 3 ? 0.001 : 0.02) * n(rng);
      f.T = f.T * se3::Exp(xi);
      f.covariance.diagonal() << 1e-6, 1e-6, 1e-6, 4e-4, 4e-4, 4e-4;
    }
  }
  auto run = [&](std::vector<DriveAdjustment::Drive> drives, int rounds, double min_factor = 1.0) {
    DriveAdjustment::Options opt;
    opt.variance_component_rounds = rounds;
    opt.variance_factor_min = min_factor;
    auto r = DriveAdjustment::Run(std::move(drives), opt);
    EXPECT_TRUE(r.ok()) << r.status().ToString();
    EXPECT_TRUE(r->summary.usable());
    return std::move(*r);
  };
  const DriveAdjustment::Result alone = run({{"a", a.result}}, 0);
  const DriveAdjustment::Result plain = run({{"a", a.result}, {"b", b.result}}, 0);
  const DriveAdjustment::Result vce = run({{"a", a.result}, {"b", b.result}}, 10);
  const DriveAdjustment::Result two_sided = run({{"a", a.result}, {"b", b.result}}, 10, 0.001);
  EXPECT_GE(plain.num_accepted(), 5);
  EXPECT_GE(vce.num_accepted(), 5);
  EXPECT_TRUE(plain.variance_components.empty());
  const double a_alone = MaxPositionError(alone.drives[0].result, a.true_poses);
  const double a_plain = MaxPositionError(plain.drives[0].result, a.true_poses);
  const double a_vce = MaxPositionError(vce.drives[0].result, a.true_poses);
  const double a_two_sided = MaxPositionError(two_sided.drives[0].result, a.true_poses);
  // As stated, b's fixes pull a (0.059 -> 0.085 m when written); with the estimated variance
  // components a is no worse than adjusted alone (0.059 m; 0.054 m with the relative factors
  // estimated both ways).
  EXPECT_GT(a_plain, a_alone + 0.02);
  EXPECT_LT(a_vce, a_alone + 0.005);
  EXPECT_LT(a_two_sided, a_alone + 0.005);
  const auto factor = [&](const std::string& drive, SubmapFactorKind kind,
                          const DriveAdjustment::Result& r) {
    for (const auto& c : r.variance_components) {
      if (c.drive == drive && c.kind == kind) {
        EXPECT_TRUE(c.estimated);
        return c.variance_factor;
      }
    }
    ADD_FAILURE() << "no group " << drive << " " << SubmapFactorKindName(kind);
    return 0.0;
  };
  EXPECT_GT(factor("b", SubmapFactorKind::kGnss, vce), 40.0);
  // a's fixes scatter less than stated (0.02 against 0.03 m): left as stated (min factor 1).
  EXPECT_EQ(factor("a", SubmapFactorKind::kGnss, vce), 1.0);
  EXPECT_EQ(factor("a", SubmapFactorKind::kReckon, vce), 1.0);
  // Both ways for the relative factors: a's chain is stated as it is drawn (0.96 when written),
  // the overlaps' ICP covariance (x 100) is looser than the synthetic clouds' registration
  // (0.15); the GNSS is still only loosened.
  EXPECT_GT(factor("b", SubmapFactorKind::kGnss, two_sided), 40.0);
  EXPECT_EQ(factor("a", SubmapFactorKind::kGnss, two_sided), 1.0);
  EXPECT_NEAR(factor("a", SubmapFactorKind::kReckon, two_sided), 1.0, 0.4);
  EXPECT_LT(factor("", SubmapFactorKind::kRegistration, two_sided), 0.5);
  EXPECT_GE(vce.variance_component_rounds, 2);
}

// Level 2's Gauss-Markov GNSS bias nodes (Level2Options::gnss_bias_states) in drive b's result:
// one run over all its fixes, a node per submap. Replayed into the merged graph under drive b's
// own keys, they let b's offset GNSS go: b is pulled onto a. A datum bias per drive
// (gnss_bias_sigma_m) is refused beside them, naming the drive.
TEST(DriveAdjustmentTest, ADrivesOwnGnssBiasNodesAreReplayed) {
  const Street street(1, 0.0, 8.0);
  SyntheticDrive a = MakeDrive(street, -3.0, 0.0, 100.0, Eigen::Vector3d::Zero(), 11);
  const Eigen::Vector3d offset(3.0, 4.0, 0.0);  // 5 m
  SyntheticDrive b = MakeDrive(street, 3.0, 120.0, 20.0, offset, 12);
  std::vector<SubmapGraphFactor> factors;
  int key = 0;
  const Eigen::Matrix3d S = 100.0 * Eigen::Matrix3d::Identity();
  for (SubmapGraphFactor f : b.result.factors) {
    if (f.kind == SubmapFactorKind::kGnss) {
      SubmapGraphFactor node;
      node.kind = key == 0 ? SubmapFactorKind::kGnssBias : SubmapFactorKind::kGnssBiasLink;
      node.a = node.b = -1;
      node.gnss_bias = key;
      node.gnss_bias_from = key - 1;
      node.transition = (key == 0 ? 0.0 : 0.999) * Eigen::Matrix3d::Identity();
      node.covariance = Matrix6d::Zero();
      node.covariance.topLeftCorner<3, 3>() = key == 0 ? S : (1.0 - 0.999 * 0.999) * S;
      factors.push_back(node);
      f.gnss_bias = key++;
    }
    factors.push_back(f);
  }
  b.result.factors = factors;
  {
    DriveAdjustment::Options opt;
    opt.gnss_bias_sigma_m = 10.0;
    auto r = DriveAdjustment::Run({{"a", a.result}, {"b", b.result}}, opt);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("drive 'b'"), std::string::npos) << r.status().ToString();
    EXPECT_NE(r.status().message().find("gnss_bias_sigma_m"), std::string::npos);
  }
  {
    auto r = DriveAdjustment::Run({{"a", a.result}, {"b", b.result}}, DriveAdjustment::Options());
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    EXPECT_TRUE(r->summary.usable());
    double after = 0.0;
    int accepted = 0;
    for (const auto& ov : r->overlaps) {
      if (!ov.accepted) continue;
      ++accepted;
      after = std::max(after, ov.offset_after_m);
    }
    EXPECT_GE(accepted, 5);
    EXPECT_LT(after, 0.03);
    // b is on a, and a's GNSS holds a where it is.
    Eigen::Vector3d shift_a = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < a.true_poses.size(); ++k) {
      shift_a += r->drives[0].result.submaps[k].T_world_submap.translation() -
                 a.true_poses[k].translation();
    }
    shift_a /= static_cast<double>(a.true_poses.size());
    EXPECT_LT(shift_a.norm(), 0.02);
    EXPECT_LT(MaxPositionError(r->drives[0].result, a.true_poses, shift_a), 0.05);
    EXPECT_LT(MaxPositionError(r->drives[1].result, b.true_poses, shift_a), 0.05);
  }
  // A link to a bias the drive never added is named.
  b.result.factors[0].gnss_bias_from = 7;
  b.result.factors[0].kind = SubmapFactorKind::kGnssBiasLink;
  auto bad = DriveAdjustment::Run({{"a", a.result}, {"b", b.result}}, DriveAdjustment::Options());
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("drive 'b'"), std::string::npos) << bad.status().ToString();
}

TEST(DriveAdjustmentTest, ASimilarLookingOtherStreetIsRejected) {
  const Street street(1, 0.0, 8.0);
  const Street other(2, 0.0, 8.0);  // same kind of street, other facades and poles
  SyntheticDrive a = MakeDrive(street, -3.0, 0.0, 100.0, Eigen::Vector3d::Zero(), 21);
  // Drive c maps the other street, but its poses (no GNSS: dead reckoning) put it onto a's.
  SyntheticDrive c =
      MakeDrive(other, 3.0, 100.0, 0.0, Eigen::Vector3d(1.0, 0.5, 0.0), 22, /*with_gnss=*/false);
  DriveAdjustment::Options opt;
  auto r = DriveAdjustment::Run({{"a", a.result}, {"c", c.result}}, opt);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_GT(r->overlaps.size(), 5u);
  int accepted = 0;
  for (const auto& ov : r->overlaps) {
    if (ov.accepted) ++accepted;
    if (ov.verified || ov.accepted) {
      ADD_FAILURE() << "overlap " << ov.submap_a << "-" << ov.submap_b << " " << ov.verdict
                    << " inliers " << ov.inlier_ratio << " rms " << ov.rms_m;
    }
  }
  EXPECT_EQ(accepted, 0);
}

TEST(DriveAdjustmentTest, RejectsBadInputNamingIt) {
  DriveAdjustment::Options opt;
  EXPECT_FALSE(DriveAdjustment::Run({}, opt).ok());
  auto r = DriveAdjustment::Run({{"empty", DriveResult()}}, opt);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("empty"), std::string::npos);
  opt.overlap_distance_m = -1.0;
  r = DriveAdjustment::Run({{"x", DriveResult()}}, opt);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("overlap_distance_m"), std::string::npos);
}

}  // namespace
}  // namespace slam_mms
