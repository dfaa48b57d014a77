// Every bad option value reaching MappingSystem::Create is reported by name with the rule it breaks
// (issue 10): one row per field, across the facade and the components it nests (Localizer, its
// surfel map, projective ICP, sliding window, deskewer and preintegration; SubmapManager and its
// point ICP; InsFilter and its GnssPrior). NaN is tried wherever a real-valued rule applies.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

#include "slam_mms/pipeline/mapping_system.hpp"

namespace slam_mms {
namespace {

using ::testing::HasSubstr;

struct BadOption {
  const char* name;
  std::function<void(MappingSystem::Options*)> set;
  const char* expected;  ///< Substring of the error: "<Class>::Options::<field> = <v>; <rule>".
};

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

const std::vector<BadOption>& Cases() {
  using O = MappingSystem::Options;
  static const std::vector<BadOption> cases = {
      // MappingSystem.
      {"map_voxel_m", [](O* o) { o->map_voxel_m = 0.0; },
       "MappingSystem::Options::map_voxel_m = 0; must be > 0"},
      {"map_max_range_m", [](O* o) { o->map_max_range_m = kNaN; },
       "MappingSystem::Options::map_max_range_m = nan; must be > 0"},
      {"max_pos_jump_m", [](O* o) { o->max_pos_jump_m = kNaN; },
       "MappingSystem::Options::max_pos_jump_m = nan; must be > 0"},
      {"num_threads", [](O* o) { o->num_threads = 0; },
       "MappingSystem::Options::num_threads = 0; must be in [1, 64]"},
      {"num_threads 65", [](O* o) { o->num_threads = 65; },
       "MappingSystem::Options::num_threads = 65; must be in [1, 64]"},
      {"gnss_outages",
       [](O* o) {
         o->gnss_outages = {{1.0, 2.0}, {5.0, 0.0}};
       },
       "MappingSystem::Options::gnss_outages[1] = (5.000000, 0.000000); start must be finite and "
       "duration > 0"},
      {"T_body_lidar nan", [](O* o) { o->T_body_lidar.translation().x() = kNaN; },
       "MappingSystem::Options::T_body_lidar is not finite"},
      {"T_body_lidar scaled", [](O* o) { o->T_body_lidar.linear() *= 2.0; },
       "MappingSystem::Options::T_body_lidar has a rotation that is not orthonormal"},
      // Localizer (level 1).
      {"localizer.submap_duration_s", [](O* o) { o->localizer.submap_duration_s = -1.0; },
       "Localizer::Options::submap_duration_s = -1; must be > 0"},
      {"localizer.model_radius_m", [](O* o) { o->localizer.model_radius_m = kNaN; },
       "Localizer::Options::model_radius_m = nan; must be > 0"},
      {"localizer.odom_sigma_trans_m", [](O* o) { o->localizer.odom_sigma_trans_m = 0.0; },
       "Localizer::Options::odom_sigma_trans_m = 0; must be > 0"},
      {"localizer.min_inlier_ratio", [](O* o) { o->localizer.min_inlier_ratio = 1.5; },
       "Localizer::Options::min_inlier_ratio = 1.5; must be in [0, 1]"},
      {"localizer.surfels.integrate_current_submap_only",
       [](O* o) { o->localizer.surfels.integrate_current_submap_only = true; },
       "Localizer::Options::surfels.integrate_current_submap_only = 1; must be false: a Localizer "
       "sets it from per_submap_surfels"},
      {"localizer.registration_voxel_m", [](O* o) { o->localizer.registration_voxel_m = 0.0; },
       "Localizer::Options::registration_voxel_m = 0; must be > 0"},
      {"localizer.icp.max_distance", [](O* o) { o->localizer.icp.max_distance = -0.5; },
       "ProjectiveIcp::Options::max_distance = -0.5; must be > 0"},
      {"localizer.icp.min_correspondences", [](O* o) { o->localizer.icp.min_correspondences = 3; },
       "ProjectiveIcp::Options::min_correspondences = 3; must be >= 6"},
      {"localizer.icp.degeneracy_threshold",
       [](O* o) { o->localizer.icp.degeneracy_threshold = 1.0; },
       "ProjectiveIcp::Options::degeneracy_threshold = 1; must be in (0, 1)"},
      {"localizer.window.window_size", [](O* o) { o->localizer.window.window_size = 0; },
       "SlidingWindowGraph::Options::window_size = 0; must be > 0"},
      {"localizer.window.max_solve_time_s",
       [](O* o) { o->localizer.window.max_solve_time_s = kNaN; },
       "SlidingWindowGraph::Options::max_solve_time_s = nan; must be > 0"},
      {"localizer.deskew.num_knots", [](O* o) { o->localizer.deskew.num_knots = 1; },
       "ScanDeskewer::Options::num_knots = 1; must be 0 (exact) or >= 2"},
      {"localizer.imu.max_sample_dt_s", [](O* o) { o->localizer.imu.max_sample_dt_s = 0.0; },
       "ImuPreintegration::Options::max_sample_dt_s = 0; must be > 0"},
      {"localizer.surfels.p_stable", [](O* o) { o->localizer.surfels.p_stable = 0.5; },
       "SurfelMapOptions::p_stable = 0.5; must be in (0.5, 1)"},
      {"localizer.surfels.max_radius_m",
       [](O* o) { o->localizer.surfels.max_radius_m = o->localizer.surfels.min_radius_m / 2; },
       "max_radius_m = "},
      // SubmapManager (level 2).
      {"level2.loop_distance_m", [](O* o) { o->level2.loop_distance_m = 0.0; },
       "SubmapManager::Options::loop_distance_m = 0; must be > 0"},
      {"level2.loop_min_submap_gap", [](O* o) { o->level2.loop_min_submap_gap = 0; },
       "SubmapManager::Options::loop_min_submap_gap = 0; must be >= 1"},
      {"level2.long_outage_s", [](O* o) { o->level2.long_outage_s = kNaN; },
       "SubmapManager::Options::long_outage_s = nan; must be >= 0"},
      {"level2.gnss_correlation_s", [](O* o) { o->level2.gnss_correlation_s = -1.0; },
       "SubmapManager::Options::gnss_correlation_s = -1; must be >= 0"},
      {"level2.pos_attitude_correlation_s",
       [](O* o) { o->level2.pos_attitude_correlation_s = -1.0; },
       "SubmapManager::Options::pos_attitude_correlation_s = -1; must be >= 0"},
      {"level2.max_iterations", [](O* o) { o->level2.max_iterations = 0; },
       "SubmapManager::Options::max_iterations = 0; must be >= 1"},
      {"level2.icp.num_normal_neighbors", [](O* o) { o->level2.icp.num_normal_neighbors = 2; },
       "PointIcp::Options::num_normal_neighbors = 2; must be >= 3"},
      // InsFilter (the POS) and its GnssPrior.
      {"ins.gyro_noise_density", [](O* o) { o->ins.gyro_noise_density = -1.0; },
       "InsFilter::Options::gyro_noise_density = -1; must be > 0"},
      {"ins.max_imu_gap_s", [](O* o) { o->ins.max_imu_gap_s = kNaN; },
       "InsFilter::Options::max_imu_gap_s = nan; must be > 0"},
      {"ins.gravity_mps2", [](O* o) { o->ins.gravity_mps2 = 30.0; },
       "InsFilter::Options::gravity_mps2 = 30; must be finite and <= 20"},
      {"ins.gnss.sigma_floor_horizontal_m",
       [](O* o) { o->ins.gnss.sigma_floor_horizontal_m = 0.0; },
       "sigma_floor_horizontal_m = 0; must be > 0"},
      {"ins.gnss.innovation_reject_chi2",
       [](O* o) {
         o->ins.gnss.innovation_reject_chi2 = o->ins.gnss.innovation_downweight_chi2 / 2;
       },
       "innovation_reject_chi2 = "},
      {"ins.gnss.t_body_antenna", [](O* o) { o->ins.gnss.t_body_antenna.z() = kNaN; },
       "GnssPrior::Options::t_body_antenna is not finite"},
      {"ins.gnss.min_fix_type", [](O* o) { o->ins.gnss.min_fix_type = GnssFixType::kNone; },
       "GnssPrior::Options::min_fix_type = none; must be at least single"},
  };
  return cases;
}

TEST(OptionsValidationTest, DefaultsAreValidInEveryMode) {
  for (MappingMode mode : {MappingMode::kFull, MappingMode::kGnssIns, MappingMode::kLidarOnly}) {
    MappingSystem::Options o;
    o.mode = mode;
    EXPECT_TRUE(o.Validate().ok()) << MappingModeName(mode) << ": " << o.Validate().ToString();
  }
}

TEST(OptionsValidationTest, EachBadValueIsReportedByNameWithItsRule) {
  for (const BadOption& c : Cases()) {
    MappingSystem::Options o;
    c.set(&o);
    const Status s = o.Validate();
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << c.name << ": " << s.ToString();
    EXPECT_THAT(s.message(), HasSubstr(c.expected)) << c.name;
    // Create() runs the same validation and builds nothing.
    auto system = MappingSystem::Create(o);
    EXPECT_EQ(system.status().code(), StatusCode::kInvalidArgument) << c.name;
  }
}

TEST(OptionsValidationTest, GnssInsModeDoesNotValidateTheUnusedLevels) {
  // kGnssIns runs neither level 1 nor level 2, so their options are not checked...
  MappingSystem::Options o;
  o.mode = MappingMode::kGnssIns;
  o.localizer.submap_duration_s = 0.0;
  o.level2.loop_distance_m = 0.0;
  EXPECT_TRUE(o.Validate().ok()) << o.Validate().ToString();
  // ... but the POS options are.
  o.ins.history_s = 0.0;
  EXPECT_THAT(o.Validate().message(), HasSubstr("InsFilter::Options::history_s = 0; must be > 0"));
}

}  // namespace
}  // namespace slam_mms
