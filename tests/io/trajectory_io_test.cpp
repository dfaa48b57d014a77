// TUM / KITTI / CSV trajectory files: exact round trips and error messages.
#include "slam_mms/io/trajectory_io.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include "slam_mms/core/lie.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

Trajectory RandomTrajectory(int n, bool with_covariance, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_int_distribution<int64_t> dt(1, 200000000);
  Trajectory t;
  int64_t ns = 1317042651106324297LL;
  for (int i = 0; i < n; ++i) {
    StampedPose p;
    p.stamp = Timestamp::FromNanoseconds(ns);
    ns += dt(rng);
    p.T_world_body.linear() = so3::Exp(Eigen::Vector3d(g(rng), g(rng), g(rng)));
    p.T_world_body.translation() = 1000.0 * Eigen::Vector3d(g(rng), g(rng), g(rng));
    if (with_covariance && i % 3 != 1) {
      Eigen::Matrix<double, 6, 6> a;
      for (int k = 0; k < 36; ++k) a(k / 6, k % 6) = g(rng);
      p.cov_T_world_body = a * a.transpose() * 1e-4;
    }
    EXPECT_TRUE(t.Add(p).ok());
  }
  return t;
}

void ExpectSamePoses(const Trajectory& a, const Trajectory& b, bool stamps, double tol) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    if (stamps) {
      EXPECT_EQ(a[i].stamp, b[i].stamp) << i;
    }
    EXPECT_LT((a[i].T_world_body.matrix() - b[i].T_world_body.matrix()).cwiseAbs().maxCoeff(), tol)
        << i;
  }
}

class TrajectoryIoTest : public ::testing::Test {
 protected:
  void SetUp() override { tmp_ = testing::MakeTempDir("trajectory_io"); }
  void TearDown() override { fs::remove_all(tmp_); }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(tmp_ / name) << text;
  }
  fs::path tmp_;
};

TEST_F(TrajectoryIoTest, TumRoundTripIsExactInTime) {
  const Trajectory t = RandomTrajectory(200, false, 1);
  ASSERT_TRUE(WriteTrajectoryTum(t, tmp_ / "a.tum").ok());
  auto back = ReadTrajectoryTum(tmp_ / "a.tum");
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  // Rotation through a %.17g quaternion: ~1e-15; translation exact to the last bit of %.17g.
  ExpectSamePoses(t, *back, true, 1e-12);
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_EQ(t[i].T_world_body.translation(), back->poses()[i].T_world_body.translation());
  }
  std::ifstream in(tmp_ / "a.tum");
  std::string first;
  in >> first;
  EXPECT_EQ(first, "1317042651.106324297");
}

TEST_F(TrajectoryIoTest, TumReadsOtherToolsFiles) {
  Write("b.tum",
        "# timestamp tx ty tz qx qy qz qw\n"
        "\n"
        "1305031102.175304 1.0 2.0 3.0 0 0 0 1\n"
        "1.305031102275304e+09 1.5 2.0 3.0 0 0 0.7071068 0.7071068\n");
  auto t = ReadTrajectoryTum(tmp_ / "b.tum");
  ASSERT_TRUE(t.ok()) << t.status().ToString();
  ASSERT_EQ(t->size(), 2u);
  EXPECT_EQ(t->poses()[0].stamp.nanoseconds(), 1305031102175304000LL);
  EXPECT_NEAR(t->poses()[1].stamp.nanoseconds(), 1305031102275304000LL, 1000);
  EXPECT_TRUE(t->poses()[1].T_world_body.linear().isApprox(
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1e-6));
}

TEST_F(TrajectoryIoTest, TumErrors) {
  Write("c.tum", "1.0 1 2 3 0 0 0 1\n2.0 1 2 3 0 0 1\n");
  auto s = ReadTrajectoryTum(tmp_ / "c.tum").status();
  EXPECT_THAT(s.message(), AllOf(HasSubstr("c.tum:2"), HasSubstr("7 fields, expected 8")));
  Write("c.tum", "1.0 1 2 3 0 0 0 1\n2.0 1 2 zz 0 0 0 1\n");
  s = ReadTrajectoryTum(tmp_ / "c.tum").status();
  EXPECT_THAT(s.message(), AllOf(HasSubstr("c.tum:2"), HasSubstr("field 4 (tz)")));
  Write("c.tum", "2.0 1 2 3 0 0 0 1\n1.0 1 2 3 0 0 0 1\n");
  s = ReadTrajectoryTum(tmp_ / "c.tum").status();
  EXPECT_THAT(s.message(), AllOf(HasSubstr("c.tum:2"), HasSubstr("not after")));
  Write("c.tum", "1.0 1 2 3 0 0 0 2\n");
  s = ReadTrajectoryTum(tmp_ / "c.tum").status();
  EXPECT_THAT(s.message(), HasSubstr("norm"));
  Write("c.tum", "1.0x 1 2 3 0 0 0 1\n");
  s = ReadTrajectoryTum(tmp_ / "c.tum").status();
  EXPECT_THAT(s.message(), HasSubstr("field 1 (t)"));
  EXPECT_EQ(ReadTrajectoryTum(tmp_ / "missing.tum").status().code(), StatusCode::kNotFound);
}

TEST_F(TrajectoryIoTest, KittiRoundTrip) {
  const Trajectory t = RandomTrajectory(100, false, 2);
  ASSERT_TRUE(WriteTrajectoryKitti(t, tmp_ / "a.txt").ok());
  auto poses = ReadPosesKitti(tmp_ / "a.txt");
  ASSERT_TRUE(poses.ok()) << poses.status().ToString();
  ASSERT_EQ(poses->size(), t.size());
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_EQ((*poses)[i].translation(), t[i].T_world_body.translation());
    EXPECT_LT(((*poses)[i].linear() - t[i].T_world_body.linear()).cwiseAbs().maxCoeff(), 1e-14);
  }
  std::vector<Timestamp> stamps;
  for (const auto& p : t.poses()) stamps.push_back(p.stamp);
  auto with_time = ReadTrajectoryKitti(tmp_ / "a.txt", stamps);
  ASSERT_TRUE(with_time.ok());
  ExpectSamePoses(t, *with_time, true, 1e-12);
  stamps.pop_back();
  EXPECT_EQ(ReadTrajectoryKitti(tmp_ / "a.txt", stamps).status().code(),
            StatusCode::kInvalidArgument);
  Write("b.txt", "1 0 0 0 0 1 0 0 0 0 1\n");
  EXPECT_THAT(ReadPosesKitti(tmp_ / "b.txt").status().message(),
              AllOf(HasSubstr("b.txt:1"), HasSubstr("11 numbers, expected 12")));
  Write("b.txt", "1 0 0 0 0 1 0 0 0 0 1 q\n");
  EXPECT_THAT(ReadPosesKitti(tmp_ / "b.txt").status().message(), HasSubstr("field 12 (tz)"));
  Write("b.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_THAT(ReadPosesKitti(tmp_ / "b.txt").status().message(), HasSubstr("not a rotation"));
}

TEST_F(TrajectoryIoTest, CsvRoundTripWithCovariance) {
  const Trajectory t = RandomTrajectory(60, true, 3);
  ASSERT_TRUE(WriteTrajectoryCsv(t, tmp_ / "a.csv").ok());
  auto back = ReadTrajectoryCsv(tmp_ / "a.csv");
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  ExpectSamePoses(t, *back, true, 1e-12);
  for (size_t i = 0; i < t.size(); ++i) {
    ASSERT_EQ(t[i].cov_T_world_body.has_value(), back->poses()[i].cov_T_world_body.has_value());
    if (t[i].cov_T_world_body) {
      EXPECT_EQ(*t[i].cov_T_world_body, *back->poses()[i].cov_T_world_body);  // %.17g: exact
    }
  }
}

TEST_F(TrajectoryIoTest, CsvErrors) {
  const Trajectory t = RandomTrajectory(3, true, 4);
  ASSERT_TRUE(WriteTrajectoryCsv(t, tmp_ / "a.csv").ok());
  std::ifstream in(tmp_ / "a.csv");
  std::string header, l1, l2;
  std::getline(in, header);
  std::getline(in, l1);
  std::getline(in, l2);
  // Drop one covariance value.
  Write("b.csv", header + "\n" + l1.substr(0, l1.rfind(',')) + ",\n");
  EXPECT_THAT(ReadTrajectoryCsv(tmp_ / "b.csv").status().message(),
              AllOf(HasSubstr("b.csv:2"), HasSubstr("35 of 36")));
  Write("b.csv", l1 + "\n");
  EXPECT_THAT(ReadTrajectoryCsv(tmp_ / "b.csv").status().message(), HasSubstr("header"));
  Write("b.csv", header + "\n12.5" + l1.substr(l1.find(',')) + "\n");
  EXPECT_THAT(ReadTrajectoryCsv(tmp_ / "b.csv").status().message(),
              HasSubstr("field 1 (stamp_ns)"));
}

TEST(SecondsExactTest, ParseAndFormat) {
  EXPECT_EQ(ParseSecondsExact("1317042651.106324297")->nanoseconds(), 1317042651106324297LL);
  EXPECT_EQ(ParseSecondsExact("12")->nanoseconds(), 12000000000LL);
  EXPECT_EQ(ParseSecondsExact("-0.5")->nanoseconds(), -500000000LL);
  EXPECT_EQ(ParseSecondsExact(".25")->nanoseconds(), 250000000LL);
  EXPECT_FALSE(ParseSecondsExact("1.0000000001").ok());
  EXPECT_FALSE(ParseSecondsExact("1e9").ok());
  EXPECT_FALSE(ParseSecondsExact("").ok());
  EXPECT_EQ(FormatSecondsExact(Timestamp::FromNanoseconds(-500000000LL)), "-0.500000000");
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<int64_t> u(-4000000000000000000LL, 4000000000000000000LL);
  for (int i = 0; i < 1000; ++i) {
    const Timestamp t = Timestamp::FromNanoseconds(u(rng));
    ASSERT_EQ(*ParseSecondsExact(FormatSecondsExact(t)), t) << FormatSecondsExact(t);
  }
}

}  // namespace
}  // namespace slam_mms
