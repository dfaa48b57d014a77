#include "slam_mms/surfel/surfel_renderer.hpp"

#include <sstream>

#include "core/option_error.hpp"

namespace slam_mms {

Status SurfelRendererOptions::Validate() const {
  SLAM_MMS_RETURN_IF_ERROR(projection.Validate().WithContext("SurfelRendererOptions::projection"));
  if (!(min_facing_cos >= -1.0 && min_facing_cos < 1.0)) {
    return internal::OptionError("SurfelRendererOptions", "min_facing_cos", min_facing_cos,
                                 "must be in [-1, 1)");
  }
  return OkStatus();
}

Status ValidateRenderInput(const SurfelRenderInput& input) {
  if (input.num_surfels > 0 && input.surfels == nullptr) {
    return InvalidArgumentError("SurfelRenderInput::surfels is null with num_surfels > 0");
  }
  if (input.num_surfels >= (size_t{1} << 31)) {
    return InvalidArgumentError("SurfelRenderInput::num_surfels must be < 2^31");
  }
  if (input.ids != nullptr) {
    for (size_t k = 0; k < input.num_ids; ++k) {
      if (input.ids[k] >= input.num_surfels) {
        std::ostringstream os;
        os << "SurfelRenderInput::ids[" << k << "] = " << input.ids[k]
           << "; must be < num_surfels = " << input.num_surfels;
        return InvalidArgumentError(os.str());
      }
    }
  } else if (input.num_ids > 0) {
    return InvalidArgumentError("SurfelRenderInput::ids is null with num_ids > 0");
  }
  return OkStatus();
}

}  // namespace slam_mms
