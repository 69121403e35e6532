// Fuzz target for a camera frame as the skyline frontend reads it
// (frontends/src/dataset_sensors.cc): the first byte picks the file's extension (formats are told
// by content, not by it) and the skyline source ("auto", "mask", "image"), the rest are the file.
// ReadCameraFrame checks its header (geo::ReadImageHeader) before OpenCV decodes it, for a camera
// of the size the header says when that is at most 1024 x 1024 and else of 640 x 480 (a header
// announcing more is refused from the header alone: the fuzzer's rss limit sees an allocation that
// slips through). A frame read goes through FrameSamples, so any size and content reaches the mask
// and photo extraction. Accepted failures: InputError, and std::invalid_argument, which the
// frontend turns into an InputError naming the frame.

#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "fuzz_files.h"
#include "skerry/core/input_error.h"
#include "skerry/geo/image_header.h"
#include "skerry/skyline/camera_frame.h"
#include "skerry/skyline/camera_model.h"
#include "skerry/skyline/skyline_extraction.h"
#include "skerry/skyline/skyline_residual.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  if (size == 0) return 0;
  static const char* const kExtension[] = {".pgm", ".ppm", ".png", ".jpg"};
  static const char* const kSource[] = {"auto", "mask", "image"};
  const std::string path = Scratch() + "/frame" + kExtension[data[0] % 4];
  Write(path, Bytes(data + 1, size - 1));
  int width = 640, height = 480;
  if (const auto header = skerry::geo::ReadImageHeader(path)) {
    if (header->width <= 1024 && header->height <= 1024) {
      width = header->width;
      height = header->height;
    }
  }
  try {
    const skerry::skyline::CameraModel camera(
        skerry::skyline::PinholeFromFov("camera", width, height, 70.0));
    const cv::Mat image = skerry::skyline::ReadCameraFrame(path, camera);
    if (image.cols != width || image.rows != height) std::abort();
    const auto samples =
        skerry::skyline::FrameSamples(image, camera, kSource[(data[0] / 4) % 3], 8, 0.5);
    for (const skerry::skyline::SkylineSample& s : samples) {
      // A sample is a pixel of the frame with a finite weight.
      if (!(s.pixel.x() >= 0 && s.pixel.x() < width && s.pixel.y() >= -0.5 &&
            s.pixel.y() <= height - 0.5 && std::isfinite(s.weight))) {
        std::abort();
      }
    }
  } catch (const skerry::InputError& e) {
    Rejected(e);
  } catch (const std::invalid_argument& e) {
    Rejected(e);
  }
  return 0;
}
