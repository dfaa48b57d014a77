// SubmapGraph::AddAttitudeChainFactor (backend/attitude_chain_factor.hpp): attitudes measured on
// successive submaps with correlated errors. Against closed forms: with Gauss-Markov errors the
// posterior variance of a common rotation is the generalised least-squares one of an AR(1)
// sequence, sigma^2 (1 + rho) / (N - (N - 2) rho); rho = 0 is the same as independent priors;
// the covariances are turned into world axes; the chain from a cross-covariance is the joint
// Gaussian's conditional; bad inputs are refused without touching the graph.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "slam_mms/backend/submap_graph.hpp"

namespace slam_mms {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A turning drive: submap k at 10 k m along a curve, yawing 20 deg and rolling 3 deg per submap.
std::vector<Eigen::Isometry3d> Turning(int n) {
  std::vector<Eigen::Isometry3d> T;
  Eigen::Isometry3d cur = Eigen::Isometry3d::Identity();
  for (int i = 0; i < n; ++i) {
    T.push_back(cur);
    cur = cur * Eigen::Translation3d(10.0, 0.0, 0.0) *
          Eigen::AngleAxisd(20.0 * kDeg, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(3.0 * kDeg, Eigen::Vector3d::UnitX());
  }
  return T;
}

Matrix6d Diagonal(double rot, double trans) {
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << rot * rot, rot * rot, rot * rot, trans * trans, trans * trans, trans * trans;
  return c;
}

// Submaps joined by exact-ish relative poses (1e-6 rad / m) and one GNSS fix on the first (no
// gauge), so that all share one rotation error; the POS attitude on every submap, cov_body each.
// chain: the first a prior, the rest chained with `rho`; else every one an independent prior.
SubmapGraph Build(const std::vector<Eigen::Isometry3d>& truth, const Eigen::Matrix3d& cov_body,
                  bool chain, double rho) {
  auto g = SubmapGraph::Create();
  EXPECT_TRUE(g.ok());
  for (size_t i = 0; i < truth.size(); ++i) {
    const SubmapId id = static_cast<SubmapId>(i);
    EXPECT_TRUE(g->AddSubmap(id, truth[i]).ok());
    if (i > 0) {
      EXPECT_TRUE(
          g->AddReckonFactor(id - 1, id, truth[i - 1].inverse() * truth[i], Diagonal(1e-6, 1e-6))
              .ok());
    }
    if (i == 0 || !chain) {
      Matrix6d prior = Diagonal(1.0, 1e3);
      prior.topLeftCorner<3, 3>() = cov_body;
      EXPECT_TRUE(g->AddPosePrior(id, truth[i], prior).ok());
    } else {
      auto c = GaussMarkovAttitudeChain(truth[i - 1].linear(), cov_body, truth[i].linear(),
                                        cov_body, rho);
      EXPECT_TRUE(c.ok()) << c.status().ToString();
      EXPECT_TRUE(
          g->AddAttitudeChainFactor(id - 1, id, truth[i - 1].linear(), truth[i].linear(), *c).ok());
    }
  }
  EXPECT_TRUE(g->AddGnssPrior(0, truth[0].translation(), 1e-6 * Eigen::Matrix3d::Identity()).ok());
  return std::move(g).value();
}

Eigen::Matrix3d RotationCovariance(const SubmapGraph& g, SubmapId id) {
  auto c = g.SubmapCovariance(id);
  EXPECT_TRUE(c.ok()) << c.status().ToString();
  return c.ok() ? Eigen::Matrix3d(c->topLeftCorner<3, 3>()) : Eigen::Matrix3d::Zero();
}

TEST(AttitudeChainTest, PosteriorIsTheGaussMarkovEstimateOfACommonError) {
  constexpr int kN = 6;
  const auto truth = Turning(kN);
  const double s = 0.1 * kDeg;
  const Eigen::Matrix3d cov = s * s * Eigen::Matrix3d::Identity();
  for (double rho : {0.0, std::exp(-5.0 / 60.0), std::exp(-5.0 / 600.0)}) {
    const SubmapGraph g = Build(truth, cov, /*chain=*/true, rho);
    const double expected = s * s * (1.0 + rho) / (kN - (kN - 2) * rho);
    const Eigen::Matrix3d c = RotationCovariance(g, kN - 1);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(c(k, k), expected, 0.01 * expected) << "rho " << rho << " axis " << k;
    }
    // Far from independent: six independent priors give a sixth of the variance.
    if (rho > 0.9) {
      EXPECT_GT(c(2, 2), 3.0 * s * s / kN);
    }
  }
  // rho = 0 is the same as independent priors.
  const Eigen::Matrix3d independent = RotationCovariance(Build(truth, cov, false, 0.0), 2);
  const Eigen::Matrix3d chained = RotationCovariance(Build(truth, cov, true, 0.0), 2);
  EXPECT_TRUE(chained.isApprox(independent, 1e-6)) << chained << "\n" << independent;
}

TEST(AttitudeChainTest, CovariancesAreTurnedIntoWorldAxes) {
  // Two submaps, the second rolled 90 deg: its body z is the world's -y. Both POS attitudes know
  // roll and pitch to 0.01 deg and yaw (body z) to 1 deg. In world axes the second holds the
  // first's yaw to 0.01 deg, so the first's yaw is known to 0.01 deg too, not 1 deg / sqrt(2).
  std::vector<Eigen::Isometry3d> truth(2, Eigen::Isometry3d::Identity());
  truth[1].translation() << 10.0, 0.0, 0.0;
  truth[1].linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  cov.diagonal() << std::pow(0.01 * kDeg, 2), std::pow(0.01 * kDeg, 2), std::pow(1.0 * kDeg, 2);
  for (double rho : {0.0, 0.5}) {
    const Eigen::Matrix3d c = RotationCovariance(Build(truth, cov, true, rho), 0);
    EXPECT_LT(std::sqrt(c(2, 2)), 0.02 * kDeg) << "rho " << rho;
    // World x (both submaps' body x) is held by both: correlated, more than by one alone.
    EXPECT_LE(std::sqrt(c(0, 0)), 0.01 * kDeg * 1.0001) << "rho " << rho;
  }
}

TEST(AttitudeChainTest, ACommonWorldErrorIsFollowedNotAveragedAway) {
  // Every POS attitude 0.3 deg off about world z, stated 0.1 deg; a GNSS track (two fixes 5 cm,
  // about 40 m apart) holds the heading to about 0.1 deg. Six independent priors count the one
  // error six times (0.3 x 6 / 7 = 0.26 deg); with rho = 0.99 it counts about once (0.15 deg).
  constexpr int kN = 6;
  const auto truth = Turning(kN);
  const double s = 0.1 * kDeg;
  const Eigen::Matrix3d cov = s * s * Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d R_err =
      Eigen::AngleAxisd(0.3 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  auto yaw_error_deg = [&](bool chain, double rho) {
    auto g = SubmapGraph::Create();
    EXPECT_TRUE(g.ok());
    for (int i = 0; i < kN; ++i) {
      EXPECT_TRUE(g->AddSubmap(i, truth[i]).ok());
      if (i > 0) {
        EXPECT_TRUE(
            g->AddReckonFactor(i - 1, i, truth[i - 1].inverse() * truth[i], Diagonal(1e-6, 1e-6))
                .ok());
      }
      const Eigen::Matrix3d R_meas = R_err * truth[i].linear();
      if (i == 0 || !chain) {
        Eigen::Isometry3d T = truth[i];
        T.linear() = R_meas;
        Matrix6d prior = Diagonal(1.0, 1e3);
        prior.topLeftCorner<3, 3>() = cov;
        EXPECT_TRUE(g->AddPosePrior(i, T, prior).ok());
      } else {
        const Eigen::Matrix3d R_prev = R_err * truth[i - 1].linear();
        auto c = GaussMarkovAttitudeChain(R_prev, cov, R_meas, cov, rho);
        EXPECT_TRUE(c.ok());
        EXPECT_TRUE(g->AddAttitudeChainFactor(i - 1, i, R_prev, R_meas, *c).ok());
      }
    }
    for (int i : {0, kN - 1}) {
      EXPECT_TRUE(
          g->AddGnssPrior(i, truth[i].translation(), 2.5e-3 * Eigen::Matrix3d::Identity()).ok());
    }
    EXPECT_TRUE(g->Solve(SolveTrigger::kFinish).ok());
    const Eigen::Matrix3d R = g->SubmapPose(kN - 1)->linear();
    return Eigen::AngleAxisd(R * truth[kN - 1].linear().transpose()).angle() / kDeg;
  };
  const double independent = yaw_error_deg(false, 0.0);
  const double correlated = yaw_error_deg(true, 0.99);
  EXPECT_GT(independent, 0.2);
  EXPECT_LT(correlated, independent - 0.05);
  EXPECT_GT(correlated, 0.02);  // still pulled towards the POS
}

TEST(AttitudeChainTest, FromCrossCovarianceIsTheConditionalOfTheJointGaussian) {
  // Equal isotropic marginals with cross-covariance rho sigma^2: the Gauss-Markov chain.
  const Eigen::Matrix3d Ra = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d Rb = Eigen::AngleAxisd(0.9, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const double s2 = std::pow(0.1 * kDeg, 2), rho = 0.8;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  // Cov(e_b, e_a) in body axes for a common world error eps with Cov rho s2 I: Rb^T (rho s2) Ra.
  auto c = AttitudeChainFromCrossCovariance(Ra, s2 * I, Rb, s2 * I,
                                            Rb.transpose() * (rho * s2 * I) * Ra);
  ASSERT_TRUE(c.ok()) << c.status().ToString();
  auto gm = GaussMarkovAttitudeChain(Ra, s2 * I, Rb, s2 * I, rho);
  ASSERT_TRUE(gm.ok());
  EXPECT_TRUE(c->transition.isApprox(rho * I, 1e-9)) << c->transition;
  EXPECT_TRUE(c->transition.isApprox(gm->transition, 1e-9));
  EXPECT_TRUE(
      c->covariance.isApprox((1.0 - rho * rho + kAttitudeChainMinInnovationShare) * s2 * I, 1e-9))
      << c->covariance;
  // A heading known to 0.1 deg at a and b, roll and pitch to 0.01, the headings' errors
  // correlated 0.95 and roll/pitch not at all: b's yaw follows a's, its roll and pitch do not.
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  cov.diagonal() << std::pow(0.01 * kDeg, 2), std::pow(0.01 * kDeg, 2), std::pow(0.1 * kDeg, 2);
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
  cross(2, 2) = 0.95 * cov(2, 2);
  auto yaw = AttitudeChainFromCrossCovariance(I, cov, I, cov, cross);
  ASSERT_TRUE(yaw.ok());
  EXPECT_NEAR(yaw->transition(2, 2), 0.95, 1e-9);
  EXPECT_NEAR(yaw->transition(0, 0), 0.0, 1e-9);
  EXPECT_NEAR(yaw->covariance(0, 0), (1.0 + kAttitudeChainMinInnovationShare) * cov(0, 0), 1e-15);
  // A correlation above 1 is no joint covariance.
  auto bad = AttitudeChainFromCrossCovariance(I, s2 * I, I, s2 * I, 1.2 * s2 * I);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("not positive definite"), std::string::npos);
}

TEST(AttitudeChainTest, BadInputsAreRefusedAndTheGraphIsUnchanged) {
  const auto truth = Turning(2);
  auto g = SubmapGraph::Create();
  ASSERT_TRUE(g.ok());
  ASSERT_TRUE(g->AddSubmap(0, truth[0]).ok());
  ASSERT_TRUE(g->AddSubmap(1, truth[1]).ok());
  const Eigen::Matrix3d R0 = truth[0].linear(), R1 = truth[1].linear();
  const Eigen::Matrix3d cov = 1e-6 * Eigen::Matrix3d::Identity();
  auto refused = [&](const Status& st, const std::string& what) {
    EXPECT_FALSE(st.ok()) << what;
    EXPECT_NE(st.message().find(what), std::string::npos) << st.ToString();
  };
  refused(GaussMarkovAttitudeChain(R0, cov, R1, cov, 1.5).status(), "rho = 1.5");
  refused(GaussMarkovAttitudeChain(R0, cov, R1, cov, -0.1).status(), "must be in [0, 1]");
  refused(GaussMarkovAttitudeChain(R0, cov, R1, cov, NAN).status(), "must be in [0, 1]");
  refused(GaussMarkovAttitudeChain(2.0 * R0, cov, R1, cov, 0.5).status(), "not orthonormal");
  refused(GaussMarkovAttitudeChain(R0, -cov, R1, cov, 0.5).status(), "not positive definite");
  auto good = GaussMarkovAttitudeChain(R0, cov, R1, cov, 0.5);
  ASSERT_TRUE(good.ok());
  AttitudeChain asym = *good;
  asym.covariance(0, 1) = 1e-3;
  refused(g->AddAttitudeChainFactor(0, 1, R0, R1, asym), "not symmetric");
  AttitudeChain nan = *good;
  nan.transition(1, 1) = NAN;
  refused(g->AddAttitudeChainFactor(0, 1, R0, R1, nan), "transition is not finite");
  refused(g->AddAttitudeChainFactor(0, 1, R0, 2.0 * R1, *good), "not orthonormal");
  refused(g->AddAttitudeChainFactor(0, 7, R0, R1, *good), "unknown submap 7");
  refused(g->AddAttitudeChainFactor(1, 0, R1, R0, *good), "added after");
  EXPECT_TRUE(g->Factors().empty());
  ASSERT_TRUE(g->AddAttitudeChainFactor(0, 1, R0, R1, *good).ok());
  ASSERT_EQ(g->Factors().size(), 1u);
  const SubmapGraphFactor& f = g->Factors()[0];
  EXPECT_EQ(f.kind, SubmapFactorKind::kAttitudeChain);
  EXPECT_STREQ(SubmapFactorKindName(f.kind), "attitude_chain");
  EXPECT_EQ(f.a, 0);
  EXPECT_EQ(f.b, 1);
  EXPECT_TRUE(f.T.linear().isApprox(R1));
  EXPECT_TRUE(f.T_a.linear().isApprox(R0));
  EXPECT_EQ(f.transition, good->transition);
  EXPECT_EQ(Eigen::Matrix3d(f.covariance.topLeftCorner<3, 3>()), good->covariance);
}

}  // namespace
}  // namespace slam_mms
