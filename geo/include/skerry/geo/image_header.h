#pragma once
/// \file
/// What an image file's header says (its size and bands), read by GDAL without decoding a
/// pixel: a reader checks a frame's size before it lets a decoder allocate what the header
/// announces (a 20-byte PPM announcing 30000 x 30000 16-bit pixels had OpenCV ask for 5.4 GB).

#include <optional>
#include <string>

namespace skerry::geo {

struct ImageHeader {
  int width = 0, height = 0, bands = 0;
  std::string format;  ///< GDAL's driver name: "PNG", "JPEG", "PNM", "BMP", "GTiff"
};

/// The header of a PNG, JPEG, binary PGM/PPM, BMP or TIFF image; std::nullopt when the file is
/// none of these (or its header is corrupt). Sidecar files are not looked for: a folder of
/// thousands of frames is not listed once per frame.
std::optional<ImageHeader> ReadImageHeader(const std::string& path);

}  // namespace skerry::geo
