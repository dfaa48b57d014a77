#pragma once
// DriveAdjustment: several finished drives of one area adjusted into one consistent map (what
// survey tools call strip or drive adjustment), on the level-2 graph (SubmapGraph).
//
//   1. One frame: every drive is moved into the local ENU world of the first drive (an exact rigid
//      transform between two ENU tangent frames through ECEF).
//   2. One graph: every drive's submaps and its level-2 factors as they were added (reckon,
//      map-to-map, loops, attitude priors, GNSS); optionally (Options::gnss_bias_sigma_m > 0) the
//      GNSS fixes of each drive share one GNSS bias (a constant world offset of that drive's GNSS
//      datum with a zero-mean prior), so a drive whose GNSS datum is offset moves rigidly.
//   3. Overlaps: for each submap, the nearest submaps of every other drive whose scan positions
//      come within Options::overlap_distance_m of its middle scan (a spatial hash of the scan
//      positions: the cost grows with the overlaps, not with the square of the drives).
//   4. Verification, multi-hypothesis: the submaps' registration clouds are registered (PointIcp,
//      coarse then fine) from the prior relative pose and from that pose shifted on a 3x3 grid of
//      world x/y steps of each of Options::hypothesis_offsets_m; the best result is the lowest
//      point-to-plane RMS among those with at least min_inlier_ratio inliers; the pair is
//      accepted where that RMS is at most max_rms_m and at most max_rms_ratio_to_self times the
//      RMS with which the source submap fits its own drive's neighbour (a different place that
//      looks alike fits clearly worse than the same place does), and no hypothesis that ends at a
//      different pose (beyond hypothesis_agreement_m / _rad) fits about as well (at least
//      ambiguity_ratio of the inliers and an RMS within 1 / ambiguity_ratio of the best):
//      repetitive or similar-looking places are rejected, not guessed.
//   5. Solve and reject: the graph is solved (every node free); an accepted overlap whose
//      whitened residual then exceeds consistency_gate_chi2 contradicts the rest (GNSS, the
//      drives' chains, the other overlaps) and is removed, and the graph solved again (at most
//      max_rejection_rounds).
//   6. By default (Options::variance_component_rounds), variance component estimation: what
//      each drive states about its own uncertainty is checked against the others. Per group
//      (a drive's factors of one kind; the overlaps), sum chi2 / sum redundancy is its variance
//      factor; the group's covariances are scaled by it and the graph solved again, until the
//      factors settle (groups are only loosened by default, and GNSS and POS attitude never
//      tightened: Options::variance_factor_min). A drive whose chain or attitude is stated
//      tighter than it is then stops pulling the others by more than it is worth.
//
// The result holds every drive with its adjusted submap poses (scan poses follow rigidly), every
// overlap tested with its verdict and its offset before and after (the translation between the
// two drives' maps there that the registration measured, under the input and the adjusted poses),
// and each drive's GNSS bias.
//
// Thread safety: Run is a pure function (uses Options::num_threads threads).

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "slam_mms/backend/solve_summary.hpp"
#include "slam_mms/backend/submap_graph.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/drive_result.hpp"
#include "slam_mms/registration/registration_options.hpp"

namespace slam_mms {

class DriveAdjustment {
 public:
  struct Options {
    double overlap_distance_m = 15.0;  ///< Scan positions of two submaps this close [m], > 0.
    int max_pairs_per_submap = 2;      ///< Nearest submaps of each other drive tested, >= 1.
    /// Grid steps of the world x/y shifts of the prior relative pose tried besides it [m] (each a
    /// 3x3 grid: 8 hypotheses); {3}: any offset within +-4.5 m starts within 1.5 m per axis.
    std::vector<double> hypothesis_offsets_m = {3.0};
    double coarse_correspondence_m = 3.0;  ///< ICP association distance, coarse pass [m], > 0.
    double fine_correspondence_m = 0.8;    ///< ICP association distance, fine pass [m], > 0.
    /// Of the best hypothesis, in (0, 1] (level 2's loop verification: Level2Options).
    double min_inlier_ratio = 0.5;
    double max_rms_m = 0.25;  ///< Point-to-plane RMS of the best hypothesis [m], > 0.
    /// ... and at most this times the RMS with which the source submap fits its own drive's
    /// neighbouring submap (the data's own noise level: sensor, voxels, motion), > 0.
    double max_rms_ratio_to_self = 2.0;
    double hypothesis_agreement_m = 0.3;     ///< Two hypotheses agree within this [m] ...
    double hypothesis_agreement_rad = 0.02;  ///< ... and this [rad].
    /// A disagreeing hypothesis with at least this fraction of the best's inliers and an RMS
    /// within 1 / ambiguity_ratio of the best's: ambiguous, in (0, 1].
    double ambiguity_ratio = 0.9;
    /// Whitened squared residual of an accepted overlap after the solve above which it is
    /// rejected as inconsistent (6 DoF), > 0.
    double consistency_gate_chi2 = 50.0;
    int max_rejection_rounds = 3;  ///< >= 0.
    /// Registration covariance: the ICP's, scaled by this and floored (as level 2's map-to-map).
    double registration_covariance_scale = 100.0;
    double registration_sigma_floor_rad = 0.001;
    double registration_sigma_floor_m = 0.02;
    /// Per-drive GNSS bias prior sigma [m]: > 0 where the drives' GNSS may be on different
    /// datums (other base stations or network realisations), each drive then moving rigidly
    /// by its estimated offset. 0 (default): one datum. On three simulated drives of one city
    /// with one datum, a free bias (1 or 10 m) let each drive's GNSS be discounted and made every
    /// drive's ATE worse than with none (docs/merge.md). Refused (InvalidArgument, naming the
    /// drive) where a drive carries its own GNSS bias nodes (Level2Options::gnss_bias_states).
    double gnss_bias_sigma_m = 0.0;
    /// Keep the drives' own attitude priors (level 2's pose priors from each drive's POS).
    bool use_pose_priors = true;
    /// Cross-drive factors' robust loss (in sigmas of the whitened residual).
    RobustLoss overlap_loss = RobustLoss::Cauchy(5.0);
    /// Variance component estimation (step 6): at most this many rounds of scaling each group's
    /// stated covariances by its variance factor (sum of its factors' squared whitened residuals
    /// over the sum of their redundancy numbers, SubmapGraph::FitFactors) and solving again, >= 0
    /// (0: off). Groups: per drive, each factor kind; the cross-drive overlaps one more.
    int variance_component_rounds = 10;
    /// A group is estimated only with at least this much redundancy (its factors' residual
    /// dimensions the estimate does not absorb); others keep a factor of 1, > 0.
    double variance_component_min_redundancy = 5.0;
    /// Variance factors are clamped to [min, max], 0 < min <= 1 <= max. `min` applies to the
    /// relative factors (reckon, map-to-map registration, loops, overlaps); the factors whose
    /// errors are correlated in time (GNSS, the POS's attitude priors and chains, GNSS biases)
    /// are never tightened: after the solve their residuals show only the part of the error
    /// that varies between them. The default min 1 only loosens what a drive states: below 1,
    /// the relative factors of the simulated merge sets were estimated at 0.01-0.3 and the drives
    /// became more accurate on most of them, but not on every one (docs/merge.md, "Session 37").
    double variance_factor_min = 1.0;
    double variance_factor_max = 100.0;
    /// The merged graph's solve (the whole graph at once: more time than level 2 gives a drive).
    SubmapGraph::Options graph = DefaultGraphOptions();
    PointIcpOptions icp;
    int num_threads = 2;  ///< [1, 64].

    [[nodiscard]] Status Validate() const;
    static SubmapGraph::Options DefaultGraphOptions() {
      SubmapGraph::Options g;
      g.max_iterations = 200;
      g.max_solve_time_s = 120.0;
      return g;
    }
  };

  struct Drive {
    std::string name;
    DriveResult result;
  };

  /// One pair of submaps of two drives tested for overlap.
  struct Overlap {
    size_t drive_a = 0;  ///< Index into the drives (drive_a < drive_b).
    size_t drive_b = 0;
    SubmapId submap_a = 0;  ///< The drives' own submap ids.
    SubmapId submap_b = 0;
    double distance_m = 0.0;  ///< Nearest scan positions under the input poses.
    bool verified = false;    ///< Registration accepted it (step 4).
    bool accepted = false;    ///< In the final graph (verified and consistent, step 5).
    std::string verdict;      ///< Why it was rejected, or "accepted".
    int hypotheses_converged = 0;
    double inlier_ratio = 0.0;  ///< Of the best hypothesis.
    double rms_m = 0.0;
    double self_rms_m = 0.0;  ///< The source submap against its own neighbour (0: unknown).
    Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();  ///< Registered (verified only).
    Matrix6d covariance = Matrix6d::Identity();
    /// Translation of the registered T_a_b against the poses' [m]: input and adjusted.
    double offset_before_m = 0.0;
    double offset_after_m = 0.0;
    double rotation_before_rad = 0.0;
    double rotation_after_rad = 0.0;
  };

  /// A group of factors of the variance component estimation and its variance factor.
  struct VarianceComponent {
    std::string drive;  ///< The drive's name; empty for the cross-drive overlaps.
    SubmapFactorKind kind = SubmapFactorKind::kReckon;
    int factors = 0;
    double redundancy = 0.0;  ///< Of its factors, in the last round.
    /// Its stated covariances were scaled by this in the final solve (1 where not estimated).
    double variance_factor = 1.0;
    bool estimated = false;  ///< Enough redundancy (Options::variance_component_min_redundancy).
  };

  struct Result {
    GeodeticPoint origin;       ///< The common world: the first drive's.
    std::vector<Drive> drives;  ///< In the common world, adjusted submap poses.
    /// Per drive, per submap (in Result::drives' order): the pose as given, in the common world
    /// (the "before"; the clouds are held once, in `drives`).
    std::vector<std::vector<Eigen::Isometry3d>> T_world_submap_input;
    std::vector<Overlap> overlaps;             ///< Every pair tested.
    std::vector<Eigen::Vector3d> gnss_bias_m;  ///< Per drive (zero without biases).
    SolveSummary summary;
    int rejection_rounds = 0;
    /// Step 6's groups (empty when off) and its rounds.
    std::vector<VarianceComponent> variance_components;
    int variance_component_rounds = 0;
    /// Why step 6 stopped without estimating (a direction no factor observes, e.g. drives
    /// without GNSS); empty otherwise. The adjustment itself stands.
    std::string variance_components_skipped;
    int num_accepted() const;
  };

  /// Adjusts `drives` (at least one; each with submaps). InvalidArgument naming the drive for an
  /// empty drive or factors that name unknown submaps.
  static StatusOr<Result> Run(std::vector<Drive> drives, const Options& options);
};

}  // namespace slam_mms
