#include "skerry/skyline/skyline_extraction.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace skerry::skyline {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Skyline Empty(int width, int height) {
  Skyline s;
  s.width = width;
  s.height = height;
  s.row.assign(width, kNaN);
  s.confidence.assign(width, 0.0f);
  return s;
}

}  // namespace

int Skyline::valid_columns() const {
  int n = 0;
  for (double r : row) n += std::isfinite(r) ? 1 : 0;
  return n;
}

Skyline ExtractSkylineFromMask(const cv::Mat& mask, const MaskExtractionOptions& options) {
  if (mask.empty() || mask.type() != CV_8UC1) {
    throw std::invalid_argument("skyline mask: expected a non-empty 8-bit single-channel image");
  }
  const int w = mask.cols, h = mask.rows;
  Skyline out = Empty(w, h);
  cv::Mat sky;
  cv::threshold(mask, sky, 127, 255, cv::THRESH_BINARY);
  if (options.morphology_px > 1) {
    const cv::Mat k = cv::getStructuringElement(
        cv::MORPH_RECT, cv::Size(options.morphology_px, options.morphology_px));
    cv::morphologyEx(sky, sky, cv::MORPH_OPEN, k);
    cv::morphologyEx(sky, sky, cv::MORPH_CLOSE, k);
  }
  // Only the sky connected to the top edge: a bright patch inside the terrain (snow, a
  // mis-segmented sail) is not sky.
  cv::Mat labels;
  cv::connectedComponents(sky, labels, 4, CV_32S);
  std::vector<char> is_top;
  {
    double max_label = 0;
    cv::minMaxLoc(labels, nullptr, &max_label);
    is_top.assign(static_cast<size_t>(max_label) + 1, 0);
    for (int u = 0; u < w; ++u) {
      const int l = labels.at<int>(0, u);
      if (l > 0) is_top[l] = 1;
    }
  }
  for (int u = 0; u < w; ++u) {
    int r = 0;
    while (r < h && is_top[labels.at<int>(r, u)]) ++r;
    if (r == 0 || r == h) continue;  // no sky at the top, or sky down to the bottom
    // Sub-pixel: where the original mask crosses 127.5 between the centres of rows r-1, r.
    const double a = mask.at<uchar>(r - 1, u), b = mask.at<uchar>(r, u);
    double row = r - 0.5;
    if (a > b && a >= 127.5 && b <= 127.5) row = (r - 1) + (a - 127.5) / (a - b);
    out.row[u] = row;
    out.confidence[u] = 1.0f;
  }
  return out;
}

Skyline ExtractSkylineFromImage(const cv::Mat& image, const ImageExtractionOptions& o) {
  if (image.empty() || (image.type() != CV_8UC3 && image.type() != CV_8UC1)) {
    throw std::invalid_argument("skyline image: expected a non-empty 8-bit BGR or grey image");
  }
  const int w = image.cols, h = image.rows;
  Skyline out = Empty(w, h);
  cv::Mat grey, bgr;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
    bgr = image;
  } else {
    grey = image;
    cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  }
  // Work resolution.
  const double f = std::min(1.0, static_cast<double>(o.work_width_px) / w);
  const int sw = std::max(8, static_cast<int>(std::lround(w * f)));
  const int sh = std::max(8, static_cast<int>(std::lround(h * f)));
  cv::Mat small, small_bgr;
  cv::resize(grey, small, cv::Size(sw, sh), 0, 0, cv::INTER_AREA);
  cv::resize(bgr, small_bgr, cv::Size(sw, sh), 0, 0, cv::INTER_AREA);
  cv::Mat g;
  small.convertTo(g, CV_32F, 1.0 / 255.0);
  cv::GaussianBlur(g, g, cv::Size(3, 3), 0);
  // Sky likelihood: bright, smooth, blue or unsaturated.
  cv::Mat hsv;
  cv::cvtColor(small_bgr, hsv, cv::COLOR_BGR2HSV);
  cv::Mat small_bgr_f;
  small_bgr.convertTo(small_bgr_f, CV_32FC3, 1.0 / 255.0);
  cv::Mat gx, gy;
  cv::Sobel(g, gx, CV_32F, 1, 0, 3);
  cv::Sobel(g, gy, CV_32F, 0, 1, 3);
  cv::Mat texture;
  cv::magnitude(gx, gy, texture);
  cv::GaussianBlur(texture, texture, cv::Size(5, 5), 0);
  cv::Mat sky(sh, sw, CV_32F);
  for (int r = 0; r < sh; ++r) {
    for (int c = 0; c < sw; ++c) {
      const cv::Vec3b p = hsv.at<cv::Vec3b>(r, c);
      const double v = p[2] / 255.0, s = p[1] / 255.0, hue = p[0] * 2.0;
      const bool blue = hue > 180.0 && hue < 250.0;
      const double colour = (s < 0.25 || blue) ? 1.0 : std::max(0.0, 1.0 - 2.0 * (s - 0.25));
      const double bright = std::clamp((v - 0.35) / 0.4, 0.0, 1.0);
      const double smooth = std::exp(-texture.at<float>(r, c) / 0.15);
      sky.at<float>(r, c) = static_cast<float>(bright * colour * smooth);
    }
  }
  // Column cumulative sums of the sky likelihood: mean above and below any row.
  cv::Mat cum(sh + 1, sw, CV_64F, cv::Scalar(0));
  for (int r = 0; r < sh; ++r) {
    for (int c = 0; c < sw; ++c)
      cum.at<double>(r + 1, c) = cum.at<double>(r, c) + sky.at<float>(r, c);
  }
  // Score of a boundary between rows r and r + 1 in column c: the edge, and the sky likelihood
  // (less one half) summed above it minus summed below it, over the height. Where a column has
  // no sky the best boundary is the top edge, which becomes a gap below.
  cv::Mat score(sh - 1, sw, CV_64F);
  for (int r = 0; r + 1 < sh; ++r) {
    for (int c = 0; c < sw; ++c) {
      const double above = cum.at<double>(r + 1, c) - 0.5 * (r + 1);
      const double below = (cum.at<double>(sh, c) - cum.at<double>(r + 1, c)) - 0.5 * (sh - r - 1);
      // Bright above, darker below: the downward step of the smoothed grey level.
      const double up = g.at<float>(std::max(0, r - 1), c) + g.at<float>(r, c);
      const double down = g.at<float>(r + 1, c) + g.at<float>(std::min(sh - 1, r + 2), c);
      const double edge = std::max(0.0, 0.5 * (up - down));
      score.at<double>(r, c) = 4.0 * edge + o.region_weight * 8.0 * (above - below) / sh;
    }
  }
  // Dynamic programming across the columns.
  const int nr = sh - 1;
  std::vector<double> prev(nr), cur(nr);
  std::vector<int> back(static_cast<size_t>(nr) * sw, 0);
  for (int r = 0; r < nr; ++r) prev[r] = score.at<double>(r, 0);
  for (int c = 1; c < sw; ++c) {
    for (int r = 0; r < nr; ++r) {
      double best = -1e300;
      int arg = r;
      for (int d = -o.max_jump_px; d <= o.max_jump_px; ++d) {
        const int rp = r + d;
        if (rp < 0 || rp >= nr) continue;
        const double v = prev[rp] - o.jump_cost * std::abs(d);
        if (v > best) {
          best = v;
          arg = rp;
        }
      }
      cur[r] = best + score.at<double>(r, c);
      back[static_cast<size_t>(c) * nr + r] = arg;
    }
    std::swap(prev, cur);
  }
  std::vector<int> path(sw);
  path[sw - 1] = static_cast<int>(std::max_element(prev.begin(), prev.end()) - prev.begin());
  for (int c = sw - 1; c > 0; --c) path[c - 1] = back[static_cast<size_t>(c) * nr + path[c]];

  // Full resolution: per column, the strongest downward step of the smoothed grey level within
  // a work pixel of the path, sub-pixel by a parabola.
  cv::Mat full;
  grey.convertTo(full, CV_32F, 1.0 / 255.0);
  cv::GaussianBlur(full, full, cv::Size(1, 5), 0);
  const double inv = 1.0 / f;
  for (int u = 0; u < w; ++u) {
    const int c = std::clamp(static_cast<int>(u * f), 0, sw - 1);
    const double centre = (path[c] + 0.5 + 0.5) * inv - 0.5;  // the boundary row at full size
    const int lo = std::max(1, static_cast<int>(centre - 1.5 * inv - 2));
    const int hi = std::min(h - 3, static_cast<int>(centre + 1.5 * inv + 2));
    double best = 0.0;
    int arg = -1;
    std::vector<double> step(static_cast<size_t>(std::max(0, hi - lo + 1)), 0.0);
    for (int r = lo; r <= hi; ++r) {
      // Step between rows r and r + 1.
      const double d = full.at<float>(r, u) - full.at<float>(r + 1, u);
      step[r - lo] = d;
      if (d > best) {
        best = d;
        arg = r;
      }
    }
    if (arg < 0) continue;
    double row = arg + 0.5;
    if (arg > lo && arg < hi) {
      const double a = step[arg - 1 - lo], b = step[arg - lo], cc = step[arg + 1 - lo];
      const double den = a - 2 * b + cc;
      if (den < 0) row += std::clamp(0.5 * (a - cc) / den, -0.5, 0.5);
    }
    // Confidence: the step's contrast (0.15 of full scale counts as sure) and the sky
    // likelihood above the boundary (a boundary at the top edge has none: no sky there).
    const int rs = static_cast<int>(row * f) - 1;
    if (rs < 1) continue;
    const double sky_above = cum.at<double>(rs + 1, c) / (rs + 1);
    // A cloud down on the ridge, glare or a sail: what lies just above the boundary is unlike
    // the sky at the top of the column (beyond the blue-to-pale gradient of a clear sky).
    const cv::Vec3f top = small_bgr_f.at<cv::Vec3f>(std::min(2, sh - 1), c);
    const cv::Vec3f near = small_bgr_f.at<cv::Vec3f>(std::max(0, rs - 1), c);
    const double unlike = cv::norm(top - near) / std::sqrt(3.0);
    const double colour = std::clamp(1.0 - (unlike - 0.15) / 0.15, 0.0, 1.0);
    const double conf =
        std::clamp(best / 0.15, 0.0, 1.0) * std::clamp(sky_above / 0.5, 0.0, 1.0) * colour;
    if (conf < o.min_confidence) continue;
    out.row[u] = row;
    out.confidence[u] = static_cast<float>(conf);
  }
  return out;
}

bool LooksLikeMask(const cv::Mat& image) {
  if (image.empty() || image.type() != CV_8UC1) return false;
  int extreme = 0, other = 0;
  for (int r = 0; r < image.rows; r += 4) {
    const uchar* p = image.ptr<uchar>(r);
    for (int c = 0; c < image.cols; c += 4) (p[c] == 0 || p[c] == 255 ? extreme : other)++;
  }
  return other <= 0.02 * (extreme + other);
}

void RequireCameraSize(int width, int height, const CameraModel& camera) {
  if (width != camera.width() || height != camera.height()) {
    throw std::invalid_argument("image is " + std::to_string(width) + "x" + std::to_string(height) +
                                ", the camera's " + std::to_string(camera.width()) + "x" +
                                std::to_string(camera.height()));
  }
}

void RequireCameraSize(const cv::Mat& image, const CameraModel& camera) {
  RequireCameraSize(image.cols, image.rows, camera);
}

std::vector<SkylineSample> SkylineSamples(const Skyline& skyline,
                                          int stride,
                                          double min_confidence) {
  std::vector<SkylineSample> out;
  stride = std::max(1, stride);
  for (int u = stride / 2; u < skyline.width; u += stride) {
    const double r = skyline.row[u];
    if (!std::isfinite(r) || skyline.confidence[u] < min_confidence) continue;
    out.push_back({Eigen::Vector2d(u, r), static_cast<double>(skyline.confidence[u])});
  }
  return out;
}

std::vector<SkylineSample> FrameSamples(const cv::Mat& image,
                                        const CameraModel& camera,
                                        const std::string& source,
                                        int stride,
                                        double min_confidence) {
  if (source != "auto" && source != "mask" && source != "image") {
    throw std::invalid_argument("unknown skyline source '" + source + "'");
  }
  RequireCameraSize(image, camera);
  Skyline sky;
  if (source == "mask" || (source == "auto" && LooksLikeMask(image))) {
    if (image.type() != CV_8UC1) {
      throw std::invalid_argument("a segmentation mask must be 8-bit single-channel");
    }
    sky = ExtractSkylineFromMask(image);
  } else {
    cv::Mat photo = image;
    if (image.type() == CV_8UC4) cv::cvtColor(image, photo, cv::COLOR_BGRA2BGR);
    sky = ExtractSkylineFromImage(photo);
  }
  return SkylineSamples(sky, stride, min_confidence);
}

}  // namespace skerry::skyline
