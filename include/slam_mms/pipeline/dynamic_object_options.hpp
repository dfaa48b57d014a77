#pragma once
// How level 1 keeps moving objects out of registration and out of the surfel map
// (Localizer::Options::dynamic; config keys "localizer.dynamic.*"). The paper does not treat
// moving objects; its scan-to-map registration is pulled by them. The worst case is traffic that
// moves with the vehicle (the car ahead and the one behind starting from a traffic light): their
// faces across the street are where most of a street canyon's along-track information is, and
// they say "the vehicle did not move".
//
// The method (a removal-first filter in the spirit of RF-LIO, Qian et al. 2021, on SuMa's range
// images): the scan's range image is cut into objects (connected components of non-ground pixels,
// split at depth jumps with the angle criterion of Bogoslavskyi & Stachniss 2016). Each object is
// compared with the surfel model rendered at the motion prediction, and only where that comes from
// the POS or the IMU (good to a centimetre over a scan interval; kFull, and F_Prein in outages),
// and only against the surfels created over the last few metres of travel, which have not
// drifted against the scan (a car that waited at a light with the vehicle is judged against its
// surfels from the wait; a tree passed 30 m ago is not judged). Correspondences the registration
// would not use (beyond its distance and normal gates) are not counted. An object whose median
// point-to-plane residual exceeds the threshold on one side for most of its pixels is moving: its
// pixels are left out of registration, surfel fusion and the map, and the model surfels it was
// seen through are removed.
//
// Not in LiDAR-only mode: a constant-velocity prediction is off by up to a metre at a submap's
// start and by the drift in degenerate streets, and a registration pulled by moving objects is no
// judge either; tried on real KITTI 0013 (judged at the prediction, or at a first registration
// and registering again), both flagged static trees and poles and made t_rel worse (1.21 % ->
// 1.27 % / 1.58 %).
//
// Thread safety: plain values.

#include "slam_mms/core/status.hpp"

namespace slam_mms {

struct DynamicObjectOptions {
  /// Off: every pixel is registered and fused (the paper's level 1).
  bool enabled = true;
  /// Objects with fewer pixels that have a model correspondence are not judged.
  int min_object_pixels = 30;
  /// Segmentation: two neighbouring pixels belong to one object when the angle between the
  /// line through their points and the farther point's ray exceeds this [deg] (Bogoslavskyi &
  /// Stachniss 2016: 10).
  double segmentation_angle_deg = 10.0;
  /// Pixels whose normal is within this angle of the vertical are ground-like and join no object
  /// (a road links every object standing on it) [deg].
  double ground_max_tilt_deg = 25.0;
  /// Threshold on an object's median |residual|: max(min_residual_m, residual_sigmas x the robust
  /// (MAD) sigma of all pixels' residuals), so a pose known less well raises it [m, -].
  double min_residual_m = 0.1;
  double residual_sigmas = 4.0;
  /// Objects are judged against the surfels created within this much travel of the vehicle (the
  /// map behind has drifted against the scan by about level 1's drift over that travel, which
  /// registration is there to correct) [m].
  double max_model_travel_m = 5.0;
  /// Moving also requires this share of the object's pixels beyond the threshold on one side.
  double min_outlier_fraction = 0.5;

  /// InvalidArgument naming "DynamicObjectOptions::<field>".
  [[nodiscard]] Status Validate() const;
};

}  // namespace slam_mms
