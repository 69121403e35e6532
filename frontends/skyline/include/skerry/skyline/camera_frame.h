#pragma once
/// \file
/// A camera frame read from its file for the skyline frontend: its header checked against the
/// camera before a pixel is decoded, so that a corrupt frame is an error naming it rather than
/// a decoder allocating what its header announces (OpenCV sizes the image from the header first:
/// a 20-byte PPM announcing 30000 x 30000 16-bit pixels asked for 5.4 GB).

#include <opencv2/core.hpp>
#include <string>

#include "skerry/skyline/camera_model.h"

namespace skerry::skyline {

/// The frame at `path`, as OpenCV decodes it (IMREAD_UNCHANGED: grey, BGR or BGRA, 8 or 16
/// bit). Frames are PNG, JPEG, binary PGM/PPM, BMP or TIFF (geo::ReadImageHeader). InputError
/// (path, 0, "image") naming what is wrong: no such file, not such an image, a header of another
/// size than the camera's width x height (both sizes), or pixels that cannot be decoded.
cv::Mat ReadCameraFrame(const std::string& path, const CameraModel& camera);

}  // namespace skerry::skyline
