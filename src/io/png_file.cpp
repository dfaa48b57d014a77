#include "io/png_file.hpp"

#include <png.h>

#include <climits>
#include <string>

namespace slam_mms::io_internal {

Status WritePng(const std::filesystem::path& file, const uint8_t* pixels, int width, int height,
                int channels, size_t row_stride_bytes) {
  const std::string name = file.string();
  if (width <= 0 || height <= 0 || pixels == nullptr) {
    return InvalidArgumentError("cannot write PNG " + name + ": empty image (" +
                                std::to_string(width) + " x " + std::to_string(height) + ")");
  }
  png_uint_32 format = 0;
  switch (channels) {
    case 1: format = PNG_FORMAT_GRAY; break;
    case 3: format = PNG_FORMAT_BGR; break;
    case 4: format = PNG_FORMAT_BGRA; break;
    default:
      return InvalidArgumentError("cannot write PNG " + name + ": " + std::to_string(channels) +
                                  " channels (1, 3 or 4 expected)");
  }
  const size_t row_bytes = static_cast<size_t>(width) * static_cast<size_t>(channels);
  if (row_stride_bytes < row_bytes || row_stride_bytes > static_cast<size_t>(INT_MAX)) {
    return InvalidArgumentError("cannot write PNG " + name + ": row stride " +
                                std::to_string(row_stride_bytes) + " bytes for rows of " +
                                std::to_string(row_bytes));
  }
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = format;
  image.flags = PNG_IMAGE_FLAG_FAST;
  // The simplified API's stride counts components, not bytes (one byte each here).
  const auto stride = static_cast<png_int_32>(row_stride_bytes);
  if (png_image_write_to_file(&image, name.c_str(), /*convert_to_8bit=*/0, pixels, stride,
                              /*colormap=*/nullptr) == 0) {
    const std::string why = image.message[0] != '\0' ? image.message : "unknown libpng error";
    png_image_free(&image);
    return UnavailableError("cannot write PNG " + name + ": " + why +
                            " (missing folder or no permission?)");
  }
  return OkStatus();
}

}  // namespace slam_mms::io_internal
