#pragma once
// Private helper of the io module for the plots (eval) and the simulator's images (sim): 8-bit
// images written as PNG through libpng's simplified API (Debian libpng-dev). OpenCV's image codecs
// did this before; linking them loads GDAL and about 120 more shared libraries, which took 0.11 s
// of every process start for three PNG writes.

#include <cstddef>
#include <cstdint>
#include <filesystem>

#include "slam_mms/core/status.hpp"

namespace slam_mms::io_internal {

/// Writes rows of 8-bit pixels as a PNG file: `channels` 1 (grey), 3 (blue, green, red: OpenCV's
/// order) or 4 (blue, green, red, alpha); `row_stride_bytes` between the starts of two rows (at
/// least width * channels). Written for speed (libpng's fast flag: little compression). Errors
/// name the file: kInvalidArgument for a bad image, kUnavailable when it cannot be written.
[[nodiscard]] Status WritePng(const std::filesystem::path& file, const uint8_t* pixels, int width,
                              int height, int channels, size_t row_stride_bytes);

}  // namespace slam_mms::io_internal
