#pragma once
// The slam_mms SDK in one include (what slam_mms::slam_mms links): the MappingSystem facade and the
// four classes it is built from, with their Options and Result types, the sensor presets and the
// core types. Every installed header of the SDK's modules is reachable from this one
// (scripts/check_layers.py checks it); the rest of the implementation is private (src/).
//
//   MappingSystem  pipeline/mapping_system.hpp  levels 1 and 2 on a sensor stream
//   Localizer      pipeline/localizer.hpp       level 1: scan-to-surfel-map registration
//   SurfelMap      surfel/surfel_map.hpp        the surfel map a Localizer registers against
//   SubmapGraph    backend/submap_graph.hpp     level 2: the global graph of submaps
//   GnssPrior      ins/gnss_prior.hpp           GNSS fix screening, outages and availability
//
// Readers, writers and the offline drive runner (slam_mms::io, slam_mms::drive), metrics
// (slam_mms::eval) and the simulator (slam_mms::sim) are package components with their own
// headers: find_package(slam_mms COMPONENTS io drive eval sim).

#include "slam_mms/backend/submap_graph.hpp"
#include "slam_mms/core/geodesy.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/core/voxel_downsample.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/pipeline/localizer.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"
#include "slam_mms/pipeline/sensor_presets.hpp"
#include "slam_mms/surfel/surfel_map.hpp"
#include "slam_mms/version.hpp"
