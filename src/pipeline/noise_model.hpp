#pragma once
// The fixed noise levels, gates and margins of level 1 (Localizer) and level 2 (SubmapManager)
// that are not options: each is named and explained here, next to its use, instead of a number
// in the code (issue #19). They are part of the method, not of a sensor: a user tunes the
// Options (Level1Options' odom/cv/reg sigmas, Level2Options' reckon/GNSS sigmas and loop gates),
// not these. Every sigma is 1 sigma; rotations in rad, translations in m, in the library's
// rotation-first order.
//
// Thread safety: constants.

#include <cstddef>

namespace slam_mms::internal::noise {

// ---- Level 1 (Localizer) ------------------------------------------------------------------------

/// F_Odom with IMU states: the scan state's velocity is tied to the POS velocity (the POS is good
/// to a few cm/s while GNSS is valid) [m/s].
inline constexpr double kPosVelocityPriorSigmaMps = 0.05;
/// A new submap's reference state carries over the previous window's velocity: looser, as it is
/// the window's estimate rather than the POS's [m/s].
inline constexpr double kReferenceVelocityPriorSigmaMps = 0.1;
/// IMU bias priors at the POS's bias estimate (scan states under F_Odom, submap references):
/// accelerometer [m/s^2] and gyro [rad/s], a tactical-grade IMU's turn-on bias spread.
inline constexpr double kBiasPriorSigmaAccelMps2 = 0.05;
inline constexpr double kBiasPriorSigmaGyroRadps = 1e-3;
/// Under F_Prein the preintegration factor carries its own covariance; this diagonal one only
/// stands for it in the F_Reg consistency check and in the level-1 pose covariance: a floor plus
/// a growth per second of the scan interval dt (rotation sigma 0.002 + 0.001 dt rad,
/// translation 0.02 + 0.05 dt m).
inline constexpr double kPreintegrationSigmaRotRad = 0.002;
inline constexpr double kPreintegrationSigmaRotRadPerS = 0.001;
inline constexpr double kPreintegrationSigmaTransM = 0.02;
inline constexpr double kPreintegrationSigmaTransMPerS = 0.05;
/// Huber scale (in sigmas of the whitened residual) of the constant-velocity factor (LiDAR only)
/// and of F_Reg: beyond 3 sigma a residual counts linearly.
inline constexpr double kMotionHuberSigmas = 3.0;
inline constexpr double kRegistrationHuberSigmas = 3.0;
/// The motion prediction that F_Reg is checked against (Graham et al. 2015): the motion factor's
/// covariance inflated 4x (2 sigma) plus a floor, so that a correct registration of a scan taken
/// while the motion model is off by its own noise still passes the chi-square gate.
inline constexpr double kPredictionCovarianceInflation = 4.0;
inline constexpr double kPredictionSigmaFloorRotRad = 0.003;
inline constexpr double kPredictionSigmaFloorTransM = 0.05;
/// The gate protects the window from a wrong registration (a degenerate street, a local
/// minimum), trusting the motion prediction. When the prediction itself is off (a velocity the
/// window took from the POS over F_Odom while the POS re-converged after a long outage), every
/// later registration fails the gate, level 1 follows the prediction alone and drifts away from
/// its own map (11.6 m in 10 s on a simulated drive, docs/pipeline.md). So after this many
/// registrations in a row rejected by the gate, the next ones that are not flagged degenerate
/// are taken as they are (MotionPrediction::enforce false), until one passes the gate again. In
/// normal runs no registration is rejected at all (18 drives of 64-198 s, session 38).
inline constexpr int kRejectedRegistrationsBeforeRecovery = 3;
/// A scan's reported pose variance where the window's covariance cannot be computed and no
/// registration covariance exists (rad^2 and m^2 on every axis): "unknown", 2 m / 2 rad.
inline constexpr double kUnknownPoseVariance = 4.0;
/// The first submap's reference is the given initial pose, held (variance per axis).
inline constexpr double kAnchorPoseVariance = 1e-8;

// ---- Level 2 (SubmapManager) --------------------------------------------------------------------

/// Clouds with fewer points are not registered (too few for normals and a 6-DoF fit).
inline constexpr std::size_t kMinRegistrationPoints = 100;
/// Map-to-map and loop factor covariance: the ICP's formal covariance (which assumes independent
/// point residuals, far too optimistic for voxelised submaps) times 100, plus an additive floor
/// per axis (rotation 0.0002 rad, translation 0.02 m). The rotation floor is 6 mm at 30 m, what
/// the maps show of consecutive submaps' alignment. It was 0.001 rad (3 cm at 30 m): then a POS
/// attitude prior of 0.02-0.03 deg per submap (a POS on a tactical IMU's stated noise) outweighed
/// the registration of two overlapping submaps, and the submaps followed the POS's attitude
/// errors from one submap to the next (full's map entropy 0.1-0.3 worse, session 28).
inline constexpr double kMapToMapCovarianceScale = 100.0;
inline constexpr double kMapToMapSigmaFloorRotRad = 0.0002;
inline constexpr double kMapToMapSigmaFloorTransM = 0.02;
/// Sequential map-to-map registration (F_Reg between consecutive submaps) is used only with at
/// least this inlier ratio and when it corrects level 1's relative pose by less than 0.05 rad and
/// 1 m: consecutive submaps overlap and level 1 is good to far better than that, so a larger
/// correction is a wrong convergence.
inline constexpr double kMapToMapMinInlierRatio = 0.3;
inline constexpr double kMapToMapMaxCorrectionRotRad = 0.05;
inline constexpr double kMapToMapMaxCorrectionTransM = 1.0;
/// GNSS fixes stamped up to this long before a submap's first scan still belong to it (a fix at
/// 10 Hz may precede the first scan start by up to one period plus clock jitter) [s].
inline constexpr double kGnssBeforeSubmapS = 0.15;
/// Level2Options::gnss_bias_states: a gap between fixes longer than this starts a new run of
/// GNSS bias nodes (GnssPrior::Options::outage_timeout_s's default: the POS's new solution).
inline constexpr double kGnssBiasRunGapS = 1.5;
/// Without a next submap, fixes up to this long after the submap's end belong to it (two 10 Hz
/// periods) [s].
inline constexpr double kGnssAfterLastScanS = 0.2;
/// Attitude prior without the POS attitude: yaw free (variance 1 rad^2) and position free
/// (variance 1e4 m^2); roll and pitch get Level2Options::attitude_prior_sigma_rad.
inline constexpr double kFreeYawVariance = 1.0;
inline constexpr double kFreePositionVariance = 1e4;

}  // namespace slam_mms::internal::noise
