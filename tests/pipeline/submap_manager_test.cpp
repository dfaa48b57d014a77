// SubmapManager (level 2) on its own, through a fake SubmapSource: unknown ids, GNSS and map-to-map
// registration pulling a drifted chain of submaps onto the truth (reading the source only), no
// solve without a trigger, options validation at Create.
#include "pipeline/submap_manager.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "pipeline/pose_covariance.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {
namespace {

constexpr int kFinished = 4;    // submaps finished; one more (unfinished) is the current one
constexpr int kScans = 5;       // per submap, 1 s apart, 2 m apart along the submap's x
constexpr double kStep = 10.0;  // between submap references [m]
const Eigen::Vector3d kLever(0.5, -0.3, 1.5);

// Level 1's submaps, read-only for level 2; counts cloud reads.
class FakeSource : public SubmapSource {
 public:
  std::vector<SubmapRecord> records;
  mutable int cloud_calls = 0;
  const std::vector<SubmapRecord>& submaps() const override { return records; }
  StatusOr<PointCloud> SubmapCloud(int32_t id, CloudKind kind) const override {
    ++cloud_calls;
    for (const SubmapRecord& r : records) {
      if (r.id == id) return kind == CloudKind::kMap ? r.cloud : r.registration_cloud;
    }
    return NotFoundError("FakeSource: no submap " + std::to_string(id));
  }
};

Timestamp At(double t) { return Timestamp::FromSeconds(1000.0 + t); }

// A straight road (its frame rotated and shifted in the world): ground, two facades, boxes.
const Eigen::Isometry3d& WorldRoad() {
  static const Eigen::Isometry3d T =
      Eigen::Translation3d(100, 50, 10) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
  return T;
}
Eigen::Isometry3d TrueSubmap(int i) { return WorldRoad() * Eigen::Translation3d(kStep * i, 0, 0); }

// Level 1's drifting estimate: the last finished one 0.5 m and 1 deg off.
Eigen::Isometry3d DriftedSubmap(int i) {
  const double f = static_cast<double>(i) / (kFinished - 1);
  return TrueSubmap(i) * Eigen::Translation3d(0.3 * f, 0.4 * f, 0) *
         Eigen::AngleAxisd(f * M_PI / 180.0, Eigen::Vector3d::UnitZ());
}

// Points on the scene's planes near submap i, in its true frame.
PointCloud SceneCloud(int i) {
  std::mt19937 rng(17 + i);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double x0 = kStep * i - 8.0, x1 = kStep * i + 18.0;
  std::vector<Eigen::Vector3d> pts;
  auto face = [&](const Eigen::Vector3d& o, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                  int n) {
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d p = o + u(rng) * a + u(rng) * b;
      if (p.x() >= x0 && p.x() <= x1) pts.push_back(p);
    }
  };
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(),
                        Z = Eigen::Vector3d::UnitZ();
  face({x0, -8, -1.8}, (x1 - x0) * X, 16 * Y, 2000);  // ground
  face({x0, 8, -1.8}, (x1 - x0) * X, 6 * Z, 800);     // facades
  face({x0, -8, -1.8}, (x1 - x0) * X, 6 * Z, 800);
  for (int b = 0; b < 7; ++b) {  // 3 m boxes, alternating sides, seen whole or not at all
    const Eigen::Vector3d o(8.0 * b + 2.0, b % 2 == 0 ? 3.0 : -6.0, -1.8);
    if (o.x() < x0 || o.x() + 3.0 > x1) continue;
    face(o, 3 * Y, 3 * Z, 200);
    face(o + 3 * X, 3 * Y, 3 * Z, 200);
    face(o, 3 * X, 3 * Z, 200);
    face(o + 3 * Y, 3 * X, 3 * Z, 200);
    face(o + 3 * Z, 3 * X, 3 * Y, 200);
  }
  const Eigen::Isometry3d T_submap_road = TrueSubmap(i).inverse() * WorldRoad();
  PointCloud cloud;
  for (const Eigen::Vector3d& p : pts) cloud.Add((T_submap_road * p).cast<float>());
  return cloud;
}

SubmapRecord MakeRecord(int i) {
  SubmapRecord r;
  r.id = i;
  r.T_world_submap = DriftedSubmap(i);
  r.start = At(5.0 * i);
  r.end = At(5.0 * i + kScans - 1);
  for (int j = 0; j < kScans; ++j) {
    r.scan_indices.push_back(kScans * i + j);
    r.scan_stamps.push_back(At(5.0 * i + j));
    r.T_submap_scan.emplace_back(Eigen::Translation3d(2.0 * j, 0, 0));
    r.cov_submap_scan.push_back(1e-4 * Matrix6d::Identity());
  }
  if (i > 0) r.T_prev_this = DriftedSubmap(i - 1).inverse() * DriftedSubmap(i);
  r.cloud = SceneCloud(i);
  r.registration_cloud = r.cloud;
  r.cloud_size = r.cloud.size();
  r.finished = i < kFinished;
  return r;
}

// Fixes every 0.5 s over submap i's span: true antenna position plus 3 cm noise.
void FeedGnss(SubmapManager& mgr, int i, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 0.03);
  for (int k = 0; k <= 2 * (kScans - 1); ++k) {
    GnssMeasurement m;
    m.stamp = At(5.0 * i + 0.5 * k);
    const Eigen::Isometry3d T_world_body = TrueSubmap(i) * Eigen::Translation3d(1.0 * k, 0, 0);
    m.p_world_antenna = T_world_body * kLever + Eigen::Vector3d(n(rng), n(rng), n(rng));
    m.cov_world_antenna = 0.03 * 0.03 * Eigen::Matrix3d::Identity();
    m.type = GnssFixType::kRtkFixed;
    mgr.AddGnssMeasurement(m, kLever);
  }
}

double TransError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}
double RotErrorDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return so3::Log(Eigen::Matrix3d(a.linear().transpose() * b.linear())).norm() * 180.0 / M_PI;
}

SubmapManager::Options ChainOptions() {
  SubmapManager::Options o;
  o.use_loops = false;         // a straight chain: no loop to find
  o.gnss_correlation_s = 0.0;  // independent fixes: the expected accuracy does not hinge on it
  o.icp.max_correspondence_distance = 0.5;  // the clouds are exact: no far associations
  // The synthetic chains drift up to 1 deg and 0.5 m over a few submaps, far beyond a real level
  // 1 (the defaults' reckon, fitted to level 1 on the sweep, would take it as a 20-sigma error):
  // the reckon states a drift of that size, fixed per axis.
  o.reckon_sigma_rot_rad = 0.002;
  o.reckon_sigma_trans_m = 0.05;
  o.reckon_sigma_rot_rad_per_m = 0.0;
  o.reckon_sigma_trans_per_m = 0.0;
  return o;
}

TEST(SubmapManagerTest, UnknownSubmapIsNotFoundAndEmptyFinishSolvesNothing) {
  auto mgr = SubmapManager::Create(SubmapManager::Options());
  ASSERT_TRUE(mgr.ok()) << mgr.status().ToString();
  FakeSource source;
  auto none = (*mgr)->Finish(source);
  ASSERT_TRUE(none.ok()) << none.status().ToString();
  EXPECT_TRUE(none->empty());
  source.records.push_back(MakeRecord(0));
  auto r = (*mgr)->OnSubmapFinished(source, 7, /*gnss_returned_after_outage=*/true);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound) << r.status().ToString();
  EXPECT_NE(r.status().message().find("7"), std::string::npos) << r.status().message();
  EXPECT_EQ((*mgr)->stats().solves, 0);
  EXPECT_EQ(source.cloud_calls, 0);
  // The failed call added nothing: Finish still has no graph to solve.
  auto still_none = (*mgr)->Finish(source);
  ASSERT_TRUE(still_none.ok());
  EXPECT_TRUE(still_none->empty());
  EXPECT_EQ((*mgr)->stats().solves, 0);
}

TEST(SubmapManagerTest, GnssReturnPullsDriftedChainOntoTruthAndOnlyReadsTheSource) {
  auto mgr = SubmapManager::Create(ChainOptions(), 1);
  ASSERT_TRUE(mgr.ok()) << mgr.status().ToString();
  FakeSource source;
  source.records.push_back(MakeRecord(0));
  std::mt19937 rng(5);
  std::vector<SubmapPoseUpdate> updates;
  for (int i = 0; i < kFinished; ++i) {
    source.records.push_back(MakeRecord(i + 1));  // level 1's new current submap
    FeedGnss(**mgr, i, rng);
    const bool last = i + 1 == kFinished;
    const std::vector<SubmapRecord> before = source.records;
    auto r = (*mgr)->OnSubmapFinished(source, i, /*gnss_returned_after_outage=*/last);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    // Level 2 only reads level 1's records.
    ASSERT_EQ(source.records.size(), before.size());
    for (size_t k = 0; k < before.size(); ++k) {
      const SubmapRecord &a = before[k], &b = source.records[k];
      EXPECT_EQ(a.id, b.id);
      EXPECT_TRUE(a.T_world_submap.isApprox(b.T_world_submap, 0.0));
      EXPECT_TRUE(a.T_prev_this.isApprox(b.T_prev_this, 0.0));
      for (int j = 0; j < kScans; ++j) {
        EXPECT_TRUE(a.T_submap_scan[j].isApprox(b.T_submap_scan[j], 0.0));
      }
      EXPECT_EQ(a.registration_cloud.points(), b.registration_cloud.points());
      EXPECT_EQ(a.finished, b.finished);
    }
    if (!last) {
      EXPECT_TRUE(r->empty()) << "no trigger before submap " << i;
    }
    updates = std::move(r).value();
  }
  const auto& stats = (*mgr)->stats();
  EXPECT_EQ(stats.solves, 1);
  EXPECT_EQ(stats.map_to_map_accepted, kFinished - 1);
  EXPECT_EQ(stats.gnss_factors, kFinished * (2 * (kScans - 1) + 1));
  EXPECT_EQ(source.cloud_calls, kFinished - 1);  // the previous submap's registration cloud

  // One update per submap of the source, in its order, the unfinished current one included.
  ASSERT_EQ(updates.size(), source.records.size());
  for (int i = 0; i < kFinished; ++i) {
    EXPECT_EQ(updates[i].id, i);
    const double in_t = TransError(DriftedSubmap(i), TrueSubmap(i));
    const double out_t = TransError(updates[i].T_world_submap, TrueSubmap(i));
    const double out_r = RotErrorDeg(updates[i].T_world_submap, TrueSubmap(i));
    EXPECT_LT(out_t, 0.1) << "submap " << i << " (input " << in_t << " m)";
    // The reckon chain's yaw bias is partly kept: registration factors carry 100x the ICP
    // covariance plus a 0.0002 rad floor, against the reckon's 0.002 rad.
    EXPECT_LT(out_r, 0.4) << "submap " << i << " (input "
                          << RotErrorDeg(DriftedSubmap(i), TrueSubmap(i)) << " deg)";
  }
  EXPECT_NEAR(TransError(DriftedSubmap(kFinished - 1), TrueSubmap(kFinished - 1)), 0.5, 1e-9);
  EXPECT_NEAR(RotErrorDeg(DriftedSubmap(kFinished - 1), TrueSubmap(kFinished - 1)), 1.0, 1e-9);
  // The current submap keeps level 1's pose relative to the last finished one.
  EXPECT_EQ(updates[kFinished].id, kFinished);
  const Eigen::Isometry3d expected = updates[kFinished - 1].T_world_submap *
                                     DriftedSubmap(kFinished - 1).inverse() *
                                     DriftedSubmap(kFinished);
  EXPECT_TRUE(updates[kFinished].T_world_submap.isApprox(expected, 1e-9));
}

// Options::reckon_from_level1: F_Reckon carries level 1's own covariance of the new reference in
// the previous submap (SubmapRecord::cov_prev_this) instead of the fixed reckon_sigma_*.
TEST(SubmapManagerTest, ReckonFromLevel1CarriesTheRecordsCovariance) {
  Vector6d var;
  var << 1e-7, 2e-7, 3e-7, 1e-4, 2e-4, 3e-4;
  for (const bool from_level1 : {false, true}) {
    SubmapManager::Options o = ChainOptions();
    o.reckon_from_level1 = from_level1;
    auto mgr = SubmapManager::Create(o);
    ASSERT_TRUE(mgr.ok()) << mgr.status().ToString();
    FakeSource source;
    for (int i = 0; i < kFinished; ++i) {
      source.records.push_back(MakeRecord(i));
      source.records.back().cov_prev_this = (static_cast<double>(i + 1) * var).asDiagonal();
      ASSERT_TRUE((*mgr)->OnSubmapFinished(source, i, false).ok());
    }
    int reckons = 0;
    for (const SubmapGraphFactor& f : (*mgr)->graph().Factors()) {
      if (f.kind != SubmapFactorKind::kReckon) continue;
      ++reckons;
      const Matrix6d expected = from_level1
                                    ? Matrix6d((static_cast<double>(f.b + 1) * var).asDiagonal())
                                    : Matrix6d(internal::DiagonalPoseCovariance(
                                          o.reckon_sigma_rot_rad, o.reckon_sigma_trans_m));
      EXPECT_TRUE(f.covariance.isApprox(expected, 1e-12)) << from_level1 << " " << f.b;
    }
    EXPECT_EQ(reckons, kFinished - 1);
  }
}

// Options::reckon_sigma_*_per_m: F_Reckon's sigmas grow in quadrature with the distance between
// the two references (the reckon's translation) above the fixed floor; negative rates are refused.
TEST(SubmapManagerTest, ReckonSigmasGrowWithTheDistance) {
  SubmapManager::Options o = ChainOptions();
  o.reckon_sigma_rot_rad = 0.0003;
  o.reckon_sigma_trans_m = 0.01;
  o.reckon_sigma_rot_rad_per_m = 1e-5;
  o.reckon_sigma_trans_per_m = 4e-4;
  auto mgr = SubmapManager::Create(o);
  ASSERT_TRUE(mgr.ok()) << mgr.status().ToString();
  FakeSource source;
  for (int i = 0; i < kFinished; ++i) {
    source.records.push_back(MakeRecord(i));
    ASSERT_TRUE((*mgr)->OnSubmapFinished(source, i, false).ok());
  }
  int reckons = 0;
  for (const SubmapGraphFactor& f : (*mgr)->graph().Factors()) {
    if (f.kind != SubmapFactorKind::kReckon) continue;
    ++reckons;
    const double d = f.T.translation().norm();
    ASSERT_GT(d, 1.0);
    const Matrix6d expected = internal::DiagonalPoseCovariance(
        std::sqrt(0.0003 * 0.0003 + 1e-10 * d * d), std::sqrt(0.01 * 0.01 + 1.6e-7 * d * d));
    EXPECT_TRUE(f.covariance.isApprox(expected, 1e-12)) << f.b << " d " << d;
  }
  EXPECT_EQ(reckons, kFinished - 1);
  SubmapManager::Options bad = o;
  bad.reckon_sigma_trans_per_m = -1e-4;
  EXPECT_NE(bad.Validate().message().find("reckon_sigma_trans_per_m"), std::string::npos);
}

TEST(SubmapManagerTest, NoTriggerNoSolveUntilFinish) {
  // Loops on, but 4 submaps are fewer than loop_min_submap_gap: no candidate, so no trigger.
  SubmapManager::Options o;
  o.loop_min_submap_gap = 6;
  o.icp.max_correspondence_distance = 0.5;
  auto mgr = SubmapManager::Create(o);
  ASSERT_TRUE(mgr.ok()) << mgr.status().ToString();
  FakeSource source;
  source.records.push_back(MakeRecord(0));
  std::mt19937 rng(9);
  for (int i = 0; i < kFinished; ++i) {
    source.records.push_back(MakeRecord(i + 1));
    FeedGnss(**mgr, i, rng);
    auto r = (*mgr)->OnSubmapFinished(source, i, /*gnss_returned_after_outage=*/false);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    EXPECT_TRUE(r->empty()) << "submap " << i;
  }
  EXPECT_EQ((*mgr)->stats().solves, 0);
  EXPECT_EQ((*mgr)->stats().loops_tested, 0);
  EXPECT_EQ((*mgr)->stats().map_to_map_accepted, kFinished - 1);
  auto fin = (*mgr)->Finish(source);
  ASSERT_TRUE(fin.ok()) << fin.status().ToString();
  EXPECT_EQ((*mgr)->stats().solves, 1);
  ASSERT_EQ(fin->size(), source.records.size());
  for (size_t k = 0; k < fin->size(); ++k) EXPECT_EQ((*fin)[k].id, source.records[k].id);
  EXPECT_LT(TransError((*fin)[kFinished - 1].T_world_submap, TrueSubmap(kFinished - 1)), 0.2);
}

// A POS's attitude error is correlated over the whole drive (an initial heading error persists),
// so one error on every submap's attitude prior, taken as independent, outweighs the GNSS track
// and the registrations by the number of submaps (docs/pipeline.md, "POS attitude priors").
// Level 1 is exact here, the fixes RTK (3 cm, counted as correlated over 10 s), the POS's yaw
// 0.3 deg off on every submap with a stated 0.1 deg.
// `link_correlation` >= 0: Options::pos_attitude_cross_covariance, each POS attitude linked to
// the previous submap's with cross-covariance link_correlation x cov (`link_to_previous` false:
// linked to a submap level 2 never got, so ignored).
double YawErrorWithBiasedPosAttitudeDeg(double pos_attitude_correlation_s,
                                        double link_correlation = -1.0,
                                        bool link_to_previous = true) {
  SubmapManager::Options o = ChainOptions();
  o.gnss_correlation_s = 10.0;
  o.pos_attitude_correlation_s = pos_attitude_correlation_s;
  o.pos_attitude_cross_covariance = link_correlation >= 0.0;
  auto mgr = SubmapManager::Create(o, 1);
  if (!mgr.ok()) return NAN;
  constexpr double kDeg = M_PI / 180.0;
  FakeSource source;
  auto exact = [](int i) {
    SubmapRecord r = MakeRecord(i);
    r.T_world_submap = TrueSubmap(i);
    if (i > 0) r.T_prev_this = TrueSubmap(i - 1).inverse() * TrueSubmap(i);
    return r;
  };
  source.records.push_back(exact(0));
  std::mt19937 rng(23);
  SubmapManager::PosAttitude pos;
  pos.cov_rotation = (0.1 * kDeg) * (0.1 * kDeg) * Eigen::Matrix3d::Identity();
  for (int i = 0; i < kFinished; ++i) {
    source.records.push_back(exact(i + 1));
    FeedGnss(**mgr, i, rng);
    const Eigen::Matrix3d R_previous = pos.R_world_submap;
    pos.R_world_submap = TrueSubmap(i).linear() *
                         Eigen::AngleAxisd(0.3 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    pos.link.reset();
    if (link_correlation >= 0.0 && i > 0) {
      auto chain =
          AttitudeChainFromCrossCovariance(R_previous, pos.cov_rotation, pos.R_world_submap,
                                           pos.cov_rotation, link_correlation * pos.cov_rotation);
      if (!chain.ok()) return NAN;
      pos.link = SubmapManager::PosAttitude::Link{link_to_previous ? i - 1 : 1000, *chain};
    }
    if (!(*mgr)->OnSubmapFinished(source, i, false, pos).ok()) return NAN;
  }
  auto fin = (*mgr)->Finish(source);
  if (!fin.ok()) return NAN;
  double sum = 0.0;
  for (int i = 0; i < kFinished; ++i) {
    sum += so3::Log(Eigen::Matrix3d(TrueSubmap(i).linear().transpose() *
                                    (*fin)[i].T_world_submap.linear()))
               .z();
  }
  return sum / kFinished / kDeg;
}

TEST(SubmapManagerTest, PosAttitudePriorsWithinTheCorrelationWindowCountAsOne) {
  const double independent = YawErrorWithBiasedPosAttitudeDeg(0.0);
  const double correlated = YawErrorWithBiasedPosAttitudeDeg(60.0);
  ASSERT_TRUE(std::isfinite(independent) && std::isfinite(correlated));
  // The GNSS track (36 fixes over 38 m, 3 cm each x20 for the 10 s correlation) holds the yaw to
  // about 0.1 deg. Four independent 0.1 deg priors weigh 4x that: the yaw goes 0.3 x 4 / 5 =
  // 0.24 deg towards the POS. In a 60 s window the first prior counts whole and the three after
  // it 5 / 60 each (1.25 priors): 0.3 x 1.25 / 2.25 = 0.17 deg.
  EXPECT_GT(independent, 0.2);
  EXPECT_LT(correlated, independent - 0.05);
  EXPECT_GE(correlated, 0.0);  // still pulled towards the POS, not past the truth
}

TEST(SubmapManagerTest, PosCrossCovarianceChainsTheAttitudes) {
  const double independent = YawErrorWithBiasedPosAttitudeDeg(0.0);
  // The POS states its errors 0.99 correlated between submaps: a common error counts about once
  // ((N (1 - rho) + 2 rho) / (1 + rho) = 1.0 priors of the four): 0.3 x 1.0 / 2.0 = 0.15 deg.
  const double chained = YawErrorWithBiasedPosAttitudeDeg(0.0, 0.99);
  // Stated uncorrelated: the same as independent priors.
  const double uncorrelated = YawErrorWithBiasedPosAttitudeDeg(0.0, 0.0);
  // A link to a submap that is not the last one with a POS attitude is not used.
  const double mislinked = YawErrorWithBiasedPosAttitudeDeg(0.0, 0.99, false);
  ASSERT_TRUE(std::isfinite(independent) && std::isfinite(chained) && std::isfinite(uncorrelated) &&
              std::isfinite(mislinked));
  EXPECT_LT(chained, independent - 0.05);
  EXPECT_GT(chained, 0.05);
  EXPECT_NEAR(uncorrelated, independent, 0.005);
  EXPECT_NEAR(mislinked, independent, 1e-9);
}

// Options::gnss_bias_states: the fixes of a run of one solution class share Gauss-Markov bias
// nodes (a new node every gnss_bias_node_interval_s, each following the previous one), a new
// run starts at another class or after a gap; each fix keeps the white part of its covariance.
TEST(SubmapManagerTest, GnssBiasStatesFollowTheRunsOfEachSolutionClass) {
  for (bool float_white : {false, true}) {
    SubmapManager::Options o = ChainOptions();
    o.gnss_bias_states = true;
    if (float_white) o.gnss_bias_rtk_float.correlated_fraction = 0.0;
    auto mgr = SubmapManager::Create(o, 1);
    ASSERT_TRUE(mgr.ok()) << mgr.status().ToString();
    FakeSource source;
    source.records.push_back(MakeRecord(0));
    const double var = 0.03 * 0.03;
    for (int i = 0; i < 3; ++i) {
      source.records.push_back(MakeRecord(i + 1));
      // Fixes every 0.5 s over [5 i, 5 i + 4]: submaps 0 and 1 RTK fixed (one run: 1 s between
      // them), submap 2 float (a new run), its last fix after a 2 s gap (another).
      for (int k = 0; k <= 2 * (kScans - 1); ++k) {
        if (i == 2 && k >= 5 && k <= 7) continue;
        GnssMeasurement m;
        m.stamp = At(5.0 * i + 0.5 * k);
        m.p_world_antenna = (TrueSubmap(i) * Eigen::Translation3d(1.0 * k, 0, 0)) * kLever;
        m.cov_world_antenna = var * Eigen::Matrix3d::Identity();
        m.type = i < 2 ? GnssFixType::kRtkFixed : GnssFixType::kRtkFloat;
        (*mgr)->AddGnssMeasurement(m, kLever);
      }
      ASSERT_TRUE((*mgr)->OnSubmapFinished(source, i, false).ok());
    }
    int runs = 0, links = 0, biased = 0, white = 0;
    for (const SubmapGraphFactor& f : (*mgr)->graph().Factors()) {
      if (f.kind == SubmapFactorKind::kGnssBias) {
        ++runs;
        EXPECT_NEAR(f.covariance(0, 0), 0.9 * var, 1e-12);
      } else if (f.kind == SubmapFactorKind::kGnssBiasLink) {
        ++links;
        EXPECT_EQ(f.gnss_bias_from, f.gnss_bias - 1);
        const double phi = std::exp(-1.0 / 30.0);  // nodes 1 s apart, tau 30 s
        EXPECT_NEAR(f.transition(0, 0), phi, 1e-12);
        EXPECT_NEAR(f.covariance(1, 1), (1.0 - phi * phi) * 0.9 * var, 1e-12);
      } else if (f.kind == SubmapFactorKind::kGnss) {
        (f.gnss_bias >= 0 ? biased : white)++;
        EXPECT_NEAR(f.covariance(2, 2), f.gnss_bias >= 0 ? 0.1 * var : var, 1e-12);
      }
    }
    // Fixed: t = 0..9 s, a node each second: 1 + 9. Float: t = 10..12 (1 + 2), then 14 (1).
    EXPECT_EQ(runs, float_white ? 1 : 3);
    EXPECT_EQ(links, float_white ? 9 : 9 + 2);
    EXPECT_EQ(biased, float_white ? 18 : 18 + 6);
    EXPECT_EQ(white, float_white ? 6 : 0);
    auto fin = (*mgr)->Finish(source);
    ASSERT_TRUE(fin.ok()) << fin.status().ToString();
    EXPECT_LT(TransError((*fin)[1].T_world_submap, TrueSubmap(1)), 0.05);
  }
  SubmapManager::Options bad;
  bad.gnss_bias_rtk_fixed.correlated_fraction = 1.0;
  auto mgr = SubmapManager::Create(bad);
  ASSERT_FALSE(mgr.ok());
  EXPECT_NE(mgr.status().message().find("gnss_bias_rtk_fixed.correlated_fraction"),
            std::string::npos)
      << mgr.status().ToString();
}

TEST(SubmapManagerTest, CreateRejectsBadOptionByName) {
  SubmapManager::Options o;
  o.loop_distance_m = 0.0;
  auto mgr = SubmapManager::Create(o);
  ASSERT_FALSE(mgr.ok());
  EXPECT_EQ(mgr.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(mgr.status().message().find("SubmapManager::Options::loop_distance_m = 0; must be > 0"),
            std::string::npos)
      << mgr.status().message();
  o.loop_distance_m = 25.0;
  auto mgr2 = SubmapManager::Create(o, 0);
  ASSERT_FALSE(mgr2.ok());
  EXPECT_NE(mgr2.status().message().find("num_threads = 0; must be >= 1"), std::string::npos)
      << mgr2.status().message();
  EXPECT_TRUE(SubmapManager::Create(SubmapManager::Options()).ok());
}

}  // namespace
}  // namespace slam_mms
