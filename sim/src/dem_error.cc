#include "skerry/sim/dem_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "random.h"

namespace skerry::sim {
namespace {

// Spread below which the 3 x 3 nodes around one are water (dem_error.h).
constexpr double kLevelSpreadM = 0.1;

}  // namespace

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
  // The heights with the curvature taken out: water is level in these.
  std::vector<double> level(grid->up_m.size());
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      level[static_cast<size_t>(row) * cols + col] =
          grid->at(col, row) + grid->NodePosition(col, row).squaredNorm() / (2.0 * earth_radius_m);
    }
  }
  const auto is_water = [&](int col, int row) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int r = std::max(0, row - 1); r <= std::min(rows - 1, row + 1); ++r) {
      for (int c = std::max(0, col - 1); c <= std::min(cols - 1, col + 1); ++c) {
        const double z = level[static_cast<size_t>(r) * cols + c];
        if (!std::isfinite(z)) return false;
        lo = std::min(lo, z);
        hi = std::max(hi, z);
      }
    }
    return hi - lo < kLevelSpreadM;
  };
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
      if (!std::isfinite(grid->up_m[i]) || is_water(col, row)) continue;
      grid->up_m[i] += scale * (field.at<double>(row, col) - mean[0]);
    }
  }
}

}  // namespace skerry::sim
