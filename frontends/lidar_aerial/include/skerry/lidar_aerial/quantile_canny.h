#pragma once
/// \file
/// Canny edges (Canny 1986) with thresholds that adapt to the image: the high and low hysteresis
/// thresholds are quantiles of the gradient magnitude over the valid cells, so an orthophoto in
/// haze and one in sunlight, or a LiDAR intensity image in any unit, give edges of the same
/// density. Used alike on the aerial image (aerial_map.h) and on a scan's intensity
/// (scan_preparation.h), so that both sides of the alignment see edges the same way.

#include <opencv2/core.hpp>

namespace skerry::lidar_aerial {

struct QuantileCannyOptions {
  double blur_px = 2.0;         ///< Gaussian sigma before the gradient (<= 0.3: none)
  double high_quantile = 0.90;  ///< share of valid cells below the high threshold
  double low_quantile = 0.75;
};

/// `image`: CV_8UC1, or CV_32FC1 (stretched to 8 bits between its 1st and 99th percentile over
/// `valid` first). `valid`: CV_8UC1, nonzero where the image means something; no edge within 3
/// cells of an invalid cell (the border of the data is not an edge of the scene). Returns
/// CV_8UC1, 255 on edges.
cv::Mat QuantileCanny(const cv::Mat& image, const cv::Mat& valid, const QuantileCannyOptions& o);

}  // namespace skerry::lidar_aerial
