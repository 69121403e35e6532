#include "skerry/skyline/camera_frame.h"

#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "core/test_util.h"
#include "skerry/core/input_error.h"
#include "skerry/geo/image_header.h"

namespace skerry::skyline {
namespace {

cv::Mat Pattern(int type) {
  cv::Mat m(48, 64, type);
  cv::randu(m, 0, 255);
  return m;
}

void ExpectError(const std::string& path, const CameraModel& camera, const std::string& text) {
  try {
    ReadCameraFrame(path, camera);
    ADD_FAILURE() << path << " was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.field(), "image");
    EXPECT_NE(e.message().find(text), std::string::npos) << e.what();
  }
}

// Each format a camera writes: the header's size and bands from GDAL, the pixels from OpenCV,
// lossless formats bit for bit.
TEST(CameraFrame, ReadsTheFormatsCamerasWrite) {
  const CameraModel camera(PinholeFromFov("cam", 64, 48, 70.0));
  const std::string dir = testing::FreshDir("frames");
  const cv::Mat grey = Pattern(CV_8UC1), colour = Pattern(CV_8UC3);
  cv::Mat deep(48, 64, CV_16UC1);
  cv::randu(deep, 0, 65535);
  struct Case {
    std::string file;
    cv::Mat image;
    std::string format;
    bool lossless;
  };
  for (const Case& c :
       {Case{"grey.png", grey, "PNG", true}, Case{"deep.png", deep, "PNG", true},
        Case{"colour.jpg", colour, "JPEG", false}, Case{"grey.pgm", grey, "PNM", true},
        Case{"colour.ppm", colour, "PNM", true}, Case{"colour.bmp", colour, "BMP", true},
        Case{"deep.tif", deep, "GTiff", true}}) {
    const std::string path = dir + "/" + c.file;
    ASSERT_TRUE(cv::imwrite(path, c.image)) << path;
    const auto header = geo::ReadImageHeader(path);
    ASSERT_TRUE(header) << path;
    EXPECT_EQ(header->width, 64);
    EXPECT_EQ(header->height, 48);
    EXPECT_EQ(header->bands, c.image.channels()) << path;
    EXPECT_EQ(header->format, c.format);
    const cv::Mat read = ReadCameraFrame(path, camera);
    EXPECT_EQ(read.type(), c.image.type()) << path;
    if (c.lossless) EXPECT_EQ(cv::norm(read, c.image, cv::NORM_INF), 0.0) << path;
  }
}

// Refused from the header, before a decoder allocates what it announces: another size than the
// camera's (a 23-byte PPM announcing 30000 x 30000 16-bit RGB pixels), a format outside the
// list (ascii PGM, which OpenCV would also size from its header), a file that is no image; and
// a header that is fine over pixels that are cut short.
TEST(CameraFrame, BadFramesAreInputErrorsNamingThem) {
  const CameraModel camera(PinholeFromFov("cam", 64, 48, 70.0));
  const std::string dir = testing::FreshDir("frames");
  std::ofstream(dir + "/huge.ppm", std::ios::binary) << "P6\n30000 30000\n65535\nabc";
  ExpectError(dir + "/huge.ppm", camera, "image is 30000x30000, the camera's 64x48");
  std::ofstream(dir + "/ascii.pgm") << "P2\n64 48\n255\n0 1 2\n";
  ExpectError(dir + "/ascii.pgm", camera, "cannot be read as an image (PNG, JPEG");
  EXPECT_FALSE(geo::ReadImageHeader(dir + "/ascii.pgm"));
  std::ofstream(dir + "/text.png") << "not a png";
  ExpectError(dir + "/text.png", camera, "cannot be read as an image (PNG, JPEG");
  ExpectError(dir + "/missing.png", camera, "no such file");
  ASSERT_TRUE(cv::imwrite(dir + "/small.png", Pattern(CV_8UC1)));
  const CameraModel wide(PinholeFromFov("wide", 1920, 1080, 70.0));
  ExpectError(dir + "/small.png", wide, "image is 64x48, the camera's 1920x1080");
  // A binary PGM whose pixels stop after one row: the header is right, the pixels do not decode.
  std::ofstream(dir + "/cut.pgm", std::ios::binary) << "P5\n64 48\n255\n" << std::string(64, 'x');
  ExpectError(dir + "/cut.pgm", camera, "its pixels do not decode");
}

}  // namespace
}  // namespace skerry::skyline
