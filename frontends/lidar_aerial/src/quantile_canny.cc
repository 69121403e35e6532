#include "skerry/lidar_aerial/quantile_canny.h"

#include <algorithm>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace skerry::lidar_aerial {

namespace {

// The q-quantiles of the values of `m` (CV_32F) where `mask` is set (0 if none).
std::vector<float> Quantiles(const cv::Mat& m, const cv::Mat& mask, std::vector<double> qs) {
  std::vector<float> v;
  v.reserve(static_cast<size_t>(m.total()));
  for (int r = 0; r < m.rows; ++r) {
    const float* a = m.ptr<float>(r);
    const std::uint8_t* k = mask.ptr<std::uint8_t>(r);
    for (int c = 0; c < m.cols; ++c) {
      if (k[c] != 0) v.push_back(a[c]);
    }
  }
  std::vector<float> out;
  for (double q : qs) {
    if (v.empty()) {
      out.push_back(0.0f);
      continue;
    }
    const size_t n = std::min(
        v.size() - 1, static_cast<size_t>(std::max(0.0, q) * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n), v.end());
    out.push_back(v[n]);
  }
  return out;
}

}  // namespace

cv::Mat QuantileCanny(const cv::Mat& image, const cv::Mat& valid, const QuantileCannyOptions& o) {
  CV_Assert(image.type() == CV_8UC1 || image.type() == CV_32FC1);
  CV_Assert(valid.type() == CV_8UC1 && valid.size() == image.size());
  cv::Mat grey;
  if (image.type() == CV_8UC1) {
    grey = image;
  } else {
    const std::vector<float> q = Quantiles(image, valid, {0.01, 0.99});
    const double span = std::max(1e-12, static_cast<double>(q[1] - q[0]));
    image.convertTo(grey, CV_8U, 255.0 / span, -255.0 * q[0] / span);
  }
  cv::Mat blurred;
  if (o.blur_px > 0.3) {
    cv::GaussianBlur(grey, blurred, cv::Size(), o.blur_px);
  } else {
    blurred = grey;
  }
  cv::Mat dx, dy;
  cv::Sobel(blurred, dx, CV_16S, 1, 0, 3);
  cv::Sobel(blurred, dy, CV_16S, 0, 1, 3);
  cv::Mat fx, fy, magnitude;
  dx.convertTo(fx, CV_32F);
  dy.convertTo(fy, CV_32F);
  cv::magnitude(fx, fy, magnitude);
  cv::Mat inner;
  cv::erode(valid, inner, cv::Mat(), cv::Point(-1, -1), 3, cv::BORDER_CONSTANT, cv::Scalar(0));
  const std::vector<float> t = Quantiles(magnitude, inner, {o.high_quantile, o.low_quantile});
  const double high = std::max(1.0, static_cast<double>(t[0]));
  const double low = std::min(high, static_cast<double>(t[1]));
  cv::Mat edges;
  cv::Canny(dx, dy, edges, low, high, /*L2gradient=*/true);
  edges.setTo(0, inner == 0);
  return edges;
}

}  // namespace skerry::lidar_aerial
