#include "skerry/sim/dem_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "random.h"

namespace skerry::sim {
void AddDemError(const DemErrorSpec& spec,
                 std::uint64_t seed,
                 double earth_radius_m,
                 geo::EnuHeightGrid* grid) {
  if (!(spec.sigma_m >= 0) || !std::isfinite(spec.sigma_m)) {
    throw std::invalid_argument("AddDemError: sigma_m must be >= 0");
  }
  if (!(spec.length_m > 0) || !std::isfinite(spec.length_m)) {
    throw std::invalid_argument("AddDemError: length_m must be > 0");
  }
  if (spec.sigma_m == 0 || grid->cols < 1 || grid->rows < 1) return;
  const int cols = grid->cols, rows = grid->rows;
  // Water (the DEM level around a node: geo::EnuHeightGrid::LevelAround) keeps its height: a
  // sea or a lake is surveyed to the centimetre. Found before any node is changed.
  std::vector<char> water(grid->up_m.size(), 0);
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      water[static_cast<size_t>(row) * cols + col] = grid->LevelAround(col, row, earth_radius_m);
    }
  }
  // White noise blurred by a Gaussian of sigma length / 2 (in nodes): its covariance is
  // exp(-d^2 / (4 s^2)) = exp(-d^2 / length^2). Reflected at the borders.
  Rng rng(seed, RngStream::kDemError);
  cv::Mat field(rows, cols, CV_64F);
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) field.at<double>(row, col) = rng.Normal();
  }
  const double s = 0.5 * spec.length_m / grid->spacing_m;
  if (s > 0.25) {
    const int half = static_cast<int>(std::ceil(4.0 * s));
    cv::GaussianBlur(field, field, cv::Size(2 * half + 1, 2 * half + 1), s, s,
                     cv::BORDER_REFLECT_101);
  }
  cv::Scalar mean, stddev;
  cv::meanStdDev(field, mean, stddev);
  const double scale = stddev[0] > 0 ? spec.sigma_m / stddev[0] : 0.0;
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      const size_t i = static_cast<size_t>(row) * cols + col;
      if (!std::isfinite(grid->up_m[i]) || water[i]) continue;
      grid->up_m[i] += scale * (field.at<double>(row, col) - mean[0]);
    }
  }
}

}  // namespace skerry::sim
