#include "skerry/skyline/skyline_extraction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

namespace skerry::skyline {
namespace {

// A skyline of a few sines, its row at column u.
double TrueRow(int u) {
  return 300.0 + 60.0 * std::sin(u / 97.0) + 25.0 * std::sin(u / 23.0 + 1.0);
}

// An anti-aliased mask: each pixel's sky share is the part of it above the true skyline.
cv::Mat AntiAliasedMask(int w, int h) {
  cv::Mat m(h, w, CV_8UC1);
  for (int u = 0; u < w; ++u) {
    const double b = TrueRow(u);  // boundary in continuous rows (centres at integers)
    for (int r = 0; r < h; ++r) {
      const double share = std::clamp(b - (r - 0.5), 0.0, 1.0);
      m.at<uchar>(r, u) = static_cast<uchar>(std::lround(255.0 * share));
    }
  }
  return m;
}

TEST(SkylineExtraction, MaskSubPixelAndMorphology) {
  cv::Mat mask = AntiAliasedMask(640, 480);
  // Speckle in the sky and terrain, and a bright blob inside the terrain (not sky).
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> uu(0, 639), vv(0, 479);
  for (int i = 0; i < 300; ++i) {
    const int u = uu(rng), v = vv(rng);
    if (std::abs(v - TrueRow(u)) > 4) mask.at<uchar>(v, u) = mask.at<uchar>(v, u) ? 0 : 255;
  }
  cv::circle(mask, cv::Point(320, 430), 15, cv::Scalar(255), -1);
  const Skyline s = ExtractSkylineFromMask(mask);
  ASSERT_EQ(s.width, 640);
  int valid = 0;
  double worst = 0;
  for (int u = 3; u < 637; ++u) {
    if (!std::isfinite(s.row[u])) continue;
    ++valid;
    worst = std::max(worst, std::abs(s.row[u] - TrueRow(u)));
  }
  EXPECT_GT(valid, 620);
  // Morphology rounds the sharpest crests by a fraction of a pixel; elsewhere 1/255 quantised.
  EXPECT_LT(worst, 0.6);
  int within = 0;
  for (int u = 3; u < 637; ++u) within += std::abs(s.row[u] - TrueRow(u)) < 0.1;
  EXPECT_GT(within, 0.8 * valid);
}

TEST(SkylineExtraction, NoSkyAndBadInput) {
  const cv::Mat ground(100, 200, CV_8UC1, cv::Scalar(0));
  const Skyline s = ExtractSkylineFromMask(ground);
  EXPECT_EQ(s.valid_columns(), 0);
  const cv::Mat all_sky(100, 200, CV_8UC1, cv::Scalar(255));
  EXPECT_EQ(ExtractSkylineFromMask(all_sky).valid_columns(), 0);  // sky to the bottom
  EXPECT_THROW(ExtractSkylineFromMask(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(ExtractSkylineFromMask(cv::Mat(10, 10, CV_16UC1)), std::invalid_argument);
  EXPECT_THROW(ExtractSkylineFromImage(cv::Mat(10, 10, CV_32FC1)), std::invalid_argument);
  const CameraModel camera(PinholeFromFov("camera", 1920, 1080, 70.0));
  EXPECT_THROW(RequireCameraSize(ground, camera), std::invalid_argument);
  EXPECT_TRUE(LooksLikeMask(ground));
}

// A frame as the frontend takes it (FrameSamples): the source chooses the extraction, a BGRA
// photo is read as its BGR, and what does not fit the camera or the source is refused.
TEST(SkylineExtraction, FrameSamplesChoosesTheExtractionBySource) {
  const CameraModel camera(PinholeFromFov("camera", 640, 480, 70.0));
  const cv::Mat mask = AntiAliasedMask(640, 480);
  const auto as_mask = SkylineSamples(ExtractSkylineFromMask(mask), 8, 0.5);
  const auto as_photo = SkylineSamples(ExtractSkylineFromImage(mask), 8, 0.5);
  const auto same = [](const std::vector<SkylineSample>& a, const std::vector<SkylineSample>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i) {
      if (a[i].pixel != b[i].pixel || a[i].weight != b[i].weight) return false;
    }
    return true;
  };
  ASSERT_GT(as_mask.size(), 40u);
  ASSERT_FALSE(same(as_mask, as_photo));  // the two extractions differ on this image
  EXPECT_TRUE(same(FrameSamples(mask, camera, "auto", 8, 0.5), as_mask));
  EXPECT_TRUE(same(FrameSamples(mask, camera, "mask", 8, 0.5), as_mask));
  EXPECT_TRUE(same(FrameSamples(mask, camera, "image", 8, 0.5), as_photo));
  cv::Mat bgr, bgra;
  cv::cvtColor(mask, bgr, cv::COLOR_GRAY2BGR);
  cv::cvtColor(mask, bgra, cv::COLOR_GRAY2BGRA);
  EXPECT_TRUE(same(FrameSamples(bgra, camera, "auto", 8, 0.5),
                   SkylineSamples(ExtractSkylineFromImage(bgr), 8, 0.5)));
  EXPECT_THROW(FrameSamples(bgr, camera, "mask", 8, 0.5), std::invalid_argument);
  EXPECT_THROW(FrameSamples(mask, camera, "lidar", 8, 0.5), std::invalid_argument);
  const CameraModel wide(PinholeFromFov("camera", 1920, 1080, 70.0));
  EXPECT_THROW(FrameSamples(mask, wide, "auto", 8, 0.5), std::invalid_argument);
}

// A synthetic photo: a blue gradient sky, textured grey-brown terrain, a cloud down on the ridge.
TEST(SkylineExtraction, PhotoBoundaryAndACloudGap) {
  const int w = 960, h = 540;
  cv::Mat img(h, w, CV_8UC3);
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 18.0);
  for (int r = 0; r < h; ++r) {
    for (int u = 0; u < w; ++u) {
      const double b = TrueRow(u) * 0.9 - 20;
      if (r < b) {
        img.at<cv::Vec3b>(r, u) = cv::Vec3b(235 - r / 8, 190 - r / 10, 150 - r / 12);
      } else {
        const int t = std::clamp(static_cast<int>(90 + n(rng)), 0, 255);
        img.at<cv::Vec3b>(r, u) = cv::Vec3b(t * 0.8, t * 0.9, t);
      }
    }
  }
  cv::ellipse(img, cv::Point(700, static_cast<int>(TrueRow(700) * 0.9 - 20)), cv::Size(45, 30), 0,
              0, 360, cv::Scalar(250, 250, 250), -1);
  const Skyline s = ExtractSkylineFromImage(img);
  int good = 0, valid = 0;
  for (int u = 0; u < w; ++u) {
    if (!std::isfinite(s.row[u])) continue;
    ++valid;
    good += std::abs(s.row[u] - (TrueRow(u) * 0.9 - 20)) < 1.0;
  }
  EXPECT_GT(good, 0.85 * w);
  EXPECT_GT(good, 0.95 * valid);
  // Under the cloud's middle the skyline is hidden: a gap or, if found, not the cloud's edge.
  for (int u = 690; u <= 710; ++u) {
    if (std::isfinite(s.row[u])) {
      EXPECT_LT(std::abs(s.row[u] - (TrueRow(u) * 0.9 - 20)), 3.0);
    }
  }
}

// The real Engabreen photo: the sky shows only above the ridge in the middle-top of the frame;
// everywhere else the mountains run out of the picture (gaps) and the glacier below is bright,
// bluish and must not be taken for sky.
TEST(SkylineExtraction, EngabreenPhoto) {
  const std::string path = std::string(SKERRY_SHARED_DATA_DIR) + "/engabreen/IMG_8902.jpg";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " missing";
  cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
  const Skyline s = ExtractSkylineFromImage(img);
  // The visible ridge spans about columns 2000-2800 near the top (rows < 200).
  int in_ridge = 0, elsewhere = 0;
  for (int u = 0; u < s.width; ++u) {
    if (!std::isfinite(s.row[u])) continue;
    if (u > 1900 && u < 3000 && s.row[u] < 250) {
      ++in_ridge;
    } else {
      ++elsewhere;
    }
  }
  EXPECT_GT(in_ridge, 500);
  EXPECT_LT(elsewhere, 50);
  cv::Mat overlay = img.clone();
  for (int u = 0; u < s.width; ++u) {
    if (std::isfinite(s.row[u])) {
      cv::circle(overlay, cv::Point(u, static_cast<int>(s.row[u])), 3, cv::Scalar(0, 0, 255), -1);
    }
  }
  std::filesystem::create_directories(SKERRY_TEST_TMP_DIR);
  cv::imwrite(std::string(SKERRY_TEST_TMP_DIR) + "/engabreen_skyline.png", overlay);
}

}  // namespace
}  // namespace skerry::skyline
