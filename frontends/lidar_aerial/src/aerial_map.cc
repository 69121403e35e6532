#include "skerry/lidar_aerial/aerial_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "skerry/core/input_error.h"
#include "skerry/lidar_aerial/quantile_canny.h"

namespace skerry::lidar_aerial {

namespace {

constexpr int kLattice = 16;  // cells between exact CRS lookups
// The fewest photo pixels across a cell when a finer photo is read as block means.
constexpr double kMinPixelsPerCell = 2.0;

}  // namespace

AerialMap::AerialMap(const geo::Orthophoto& ortho,
                     const Eigen::AlignedBox2d& box_w,
                     const AerialMapOptions& options)
    : options_(options), source_(ortho.path()), resolution_m_(options.resolution_m) {
  if (!(resolution_m_ > 0.0)) {
    throw InputError(ortho.path(), 0, "resolution_m", "the map's cell size must be positive");
  }
  const Eigen::AlignedBox2d box = box_w.intersection(ortho.footprint_box_enu());
  if (box.isEmpty() || box.sizes().minCoeff() < 2.0 * resolution_m_) {
    throw InputError(ortho.path(), 0, "coverage",
                     "the requested area does not overlap the orthophoto");
  }
  const int cols = static_cast<int>(std::floor(box.sizes().x() / resolution_m_)) + 1;
  const int rows = static_cast<int>(std::floor(box.sizes().y() / resolution_m_)) + 1;
  x0_ = box.min().x();
  y1_ = box.max().y();

  // Source pixel of every cell: exact on the lattice, bilinear between.
  const int lc = (cols - 1 + kLattice - 1) / kLattice + 1;
  const int lr = (rows - 1 + kLattice - 1) / kLattice + 1;
  std::vector<Eigen::Vector2d> node(static_cast<size_t>(lc * lr));
  auto exact = [&](double c, double r) {
    const Eigen::Vector2d xy = ToEnu({c, r});
    return ortho.EnuToPixel(Eigen::Vector3d(xy.x(), xy.y(), 0.0));
  };
  for (int j = 0; j < lr; ++j) {
    for (int i = 0; i < lc; ++i)
      node[static_cast<size_t>(j * lc + i)] = exact(i * kLattice, j * kLattice);
  }
  auto interpolated = [&](double c, double r) -> Eigen::Vector2d {
    const int i = std::min(static_cast<int>(c) / kLattice, lc - 2);
    const int j = std::min(static_cast<int>(r) / kLattice, lr - 2);
    const double a = c / kLattice - i;
    const double b = r / kLattice - j;
    const auto at = [&](int ii, int jj) { return node[static_cast<size_t>(jj * lc + ii)]; };
    return ((1 - a) * (1 - b)) * at(i, j) + (a * (1 - b)) * at(i + 1, j) +
           ((1 - a) * b) * at(i, j + 1) + (a * b) * at(i + 1, j + 1);
  };
  cv::Mat map_u(rows, cols, CV_32FC1), map_v(rows, cols, CV_32FC1);
  valid_ = cv::Mat(rows, cols, CV_8UC1);
  const double w = ortho.width() - 0.5, h = ortho.height() - 0.5;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const Eigen::Vector2d uv = interpolated(c, r);
      map_u.at<float>(r, c) = static_cast<float>(uv.x());
      map_v.at<float>(r, c) = static_cast<float>(uv.y());
      const bool in =
          uv.allFinite() && uv.x() >= -0.5 && uv.x() <= w && uv.y() >= -0.5 && uv.y() <= h;
      valid_.at<std::uint8_t>(r, c) = in ? 255 : 0;
    }
  }
  for (int j = 0; j + 1 < lr; ++j) {
    for (int i = 0; i + 1 < lc; ++i) {
      const double c = (i + 0.5) * kLattice, r = (j + 0.5) * kLattice;
      lattice_error_px_ = std::max(lattice_error_px_, (interpolated(c, r) - exact(c, r)).norm());
    }
  }

  // Only the image's pixels under the cells are read (an orthophoto on disk by this window):
  // their bounding box, with a margin for the anti-aliasing blur below (OpenCV's Gaussian kernel
  // reaches 3 sigma) and the bilinear lookup, so that the window's blur is the whole image's.
  // A photo more than 2 x kMinPixelsPerCell times finer than the cells (a drone's mosaic) is
  // read as block means (Orthophoto::Pixels(window, factor)) that keep at least
  // kMinPixelsPerCell of them across a cell for the blur to anti-alias: its window at full
  // resolution may hold a billion pixels.
  const double step = resolution_m_ / ortho.ground_sample_distance_m();
  const double blur_px = step > 1.0 ? 0.5 * step : 0.0;
  const int factor = step >= 2.0 * kMinPixelsPerCell
                         ? static_cast<int>(std::min(std::floor(step / kMinPixelsPerCell), 4096.0))
                         : 1;
  const int margin = static_cast<int>(std::ceil(4.0 * blur_px)) + 2 * factor;
  float u_lo = std::numeric_limits<float>::infinity(), v_lo = u_lo, u_hi = -u_lo, v_hi = -u_lo;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const float u = map_u.at<float>(r, c), v = map_v.at<float>(r, c);
      if (!std::isfinite(u) || !std::isfinite(v)) continue;
      u_lo = std::min(u_lo, u);
      u_hi = std::max(u_hi, u);
      v_lo = std::min(v_lo, v);
      v_hi = std::max(v_hi, v);
    }
  }
  const auto pixel = [&](float x, int add) {
    return static_cast<int>(std::clamp<double>(std::floor(x) + add, 0.0, 2e9));
  };
  geo::OrthophotoPixels pixels;
  if (u_lo <= u_hi && v_lo <= v_hi) {
    // Blocks on the image's lattice of `factor` pixels, whatever the map's extent.
    const auto down = [&](int p) { return p / factor * factor; };
    const auto up = [&](int p) { return (p + factor - 1) / factor * factor; };
    const int x0 = down(pixel(u_lo, -margin)), y0 = down(pixel(v_lo, -margin));
    const int x1 = std::min(up(pixel(u_hi, margin + 2)), ortho.width());
    const int y1 = std::min(up(pixel(v_hi, margin + 2)), ortho.height());
    if (x1 > x0 && y1 > y0) pixels = ortho.Pixels(cv::Rect(x0, y0, x1 - x0, y1 - y0), factor);
  }
  if (pixels.rect.empty()) {
    throw InputError(ortho.path(), 0, "coverage",
                     "the requested area does not overlap the orthophoto's pixels");
  }
  // (A grey window may be a view of the orthophoto's image, never written to.)
  cv::Mat source;
  if (pixels.image.channels() == 1) {
    source = pixels.image;
  } else {
    cv::cvtColor(pixels.image, source, cv::COLOR_BGR2GRAY);
  }
  if (step > 1.0) {
    cv::Mat smoothed;
    cv::GaussianBlur(source, smoothed, cv::Size(), blur_px / factor);
    source = smoothed;
  }
  if (factor == 1) {
    map_u -= static_cast<float>(pixels.rect.x);
    map_v -= static_cast<float>(pixels.rect.y);
  } else {
    // A block mean sits at its block's centre (OrthophotoPixels).
    const double centre = 0.5 * (factor - 1);
    map_u.convertTo(map_u, CV_32F, 1.0 / factor, -(pixels.rect.x + centre) / factor);
    map_v.convertTo(map_v, CV_32F, 1.0 / factor, -(pixels.rect.y + centre) / factor);
  }
  cv::remap(source, grey_, map_u, map_v, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
  // Cells on image pixels without data (no-data, alpha, NaN) are as invalid as cells off the
  // image: the step from a masked area to the photo is no edge of the world.
  if (!pixels.valid.empty()) {
    cv::Mat holds_data;
    cv::remap(pixels.valid, holds_data, map_u, map_v, cv::INTER_NEAREST, cv::BORDER_CONSTANT,
              cv::Scalar(0));
    cv::bitwise_and(valid_, holds_data, valid_);
  }

  // Edges: Canny with thresholds at quantiles of the gradient magnitude; none where the image
  // ends.
  edges_ = QuantileCanny(
      grey_, valid_,
      {options_.blur_m / resolution_m_, options_.canny_high_quantile, options_.canny_low_quantile});

  // Distance to the nearest edge, metres, clipped; invalid cells at the clip.
  cv::Mat not_edge = edges_ == 0;
  cv::distanceTransform(not_edge, distance_, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  distance_ *= resolution_m_;
  cv::min(distance_, options_.max_distance_m, distance_);
  distance_.setTo(options_.max_distance_m, valid_ == 0);
}

bool AerialMap::Covers(const Eigen::Vector2d& xy_w) const {
  const Eigen::Vector2d cr = ToGrid(xy_w);
  const int c = static_cast<int>(std::lround(cr.x()));
  const int r = static_cast<int>(std::lround(cr.y()));
  return c >= 0 && r >= 0 && c < cols() && r < rows() && valid_.at<std::uint8_t>(r, c) != 0;
}

}  // namespace skerry::lidar_aerial
