#include "skerry/skyline/camera_frame.h"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

#include "skerry/core/input_error.h"
#include "skerry/geo/image_header.h"
#include "skerry/skyline/skyline_extraction.h"

namespace skerry::skyline {

namespace {

std::string Size(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

}  // namespace

cv::Mat ReadCameraFrame(const std::string& path, const CameraModel& camera) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(path, 0, "image", "no such file");
  }
  const auto header = geo::ReadImageHeader(path);
  if (!header) {
    throw InputError(path, 0, "image",
                     "cannot be read as an image (PNG, JPEG, binary PGM/PPM, BMP or TIFF)");
  }
  try {
    RequireCameraSize(header->width, header->height, camera);
  } catch (const std::invalid_argument& e) {
    throw InputError(path, 0, "image", e.what());
  }
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    throw InputError(path, 0, "image", "cannot be read as an image: its pixels do not decode");
  }
  if (image.cols != camera.width() || image.rows != camera.height()) {
    throw InputError(path, 0, "image",
                     "image decodes to " + Size(image.cols, image.rows) + ", its header says " +
                         Size(header->width, header->height));
  }
  return image;
}

}  // namespace skerry::skyline
