#pragma once
// How level 1 de-skews a scan (Localizer::Options::deskew; MappingSystem uses the same for the
// scans it places with the POS). The de-skewer itself is internal (src/pipeline); its threads
// come from the owner's one num_threads.
//
// Thread safety: plain values.

#include "slam_mms/core/status.hpp"

namespace slam_mms {

struct DeskewOptions {
  /// Number of interpolation knots over the scan; points between knots interpolate linearly.
  /// 0 = exact per-point interpolation.
  int num_knots = 64;
  /// InvalidArgument naming "ScanDeskewer::Options::num_knots".
  [[nodiscard]] Status Validate() const;
};

}  // namespace slam_mms
