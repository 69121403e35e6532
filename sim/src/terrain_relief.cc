#include "skerry/sim/terrain_relief.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "skerry/geo/footprint_strip.h"
#include "skerry/geo/terrain_sharpening.h"

namespace skerry::sim {

namespace {
constexpr int kIterations = 3;
}  // namespace

void AddTerrainRelief(const TerrainReliefSpec& spec,
                      double cell_m,
                      double earth_radius_m,
                      geo::EnuHeightGrid* world) {
  if (!(spec.gain >= 0.0) || !std::isfinite(spec.gain)) {
    throw std::invalid_argument("AddTerrainRelief: gain must be >= 0");
  }
  if (spec.gain == 0.0 || world->cols < 1 || world->rows < 1) return;
  if (!(cell_m > 0.0) || !std::isfinite(cell_m)) {
    throw std::invalid_argument("AddTerrainRelief: cell_m must be > 0");
  }
  const int cols = world->cols, rows = world->rows;
  if (!(spec.footprint_cells > 0.0) || !std::isfinite(spec.footprint_cells)) {
    throw std::invalid_argument("AddTerrainRelief: footprint_cells must be > 0");
  }
  const double s = spec.footprint_cells * cell_m / world->spacing_m;  // in nodes
  const int half = geo::FootprintHalfWidth(s, cols, rows);
  const cv::Size kernel(2 * half + 1, 2 * half + 1);
  std::vector<float> change(world->up_m.size(), 0.0f);
  // Reused by strips of one size, as geo::SharpenTerrain's.
  cv::Mat blur_valid, blur_data, denominator, z, zv, blur_z;
  for (int r0 = 0; r0 < rows; r0 += geo::kFootprintStripRows) {
    const int r1 = std::min(rows, r0 + geo::kFootprintStripRows);
    // Each iteration's blur spoils `half` rows at the halo's cut edges; after three the kept rows
    // are still clean.
    const int a = std::max(0, r0 - kIterations * half);
    const int b = std::min(rows, r1 + kIterations * half);
    const geo::FootprintStrip strip = geo::ReadFootprintStrip(*world, a, b, earth_radius_m);
    if (!strip.has_data) continue;
    // Water is no part of the land's footprint (geo::SharpenTerrain says why) and keeps its
    // height.
    const cv::Mat& y = strip.up;
    const cv::Mat& valid = strip.land;
    const cv::Mat& water = strip.water;
    // h * z over the nodes that hold data only (normalised convolution).
    cv::GaussianBlur(valid, blur_valid, kernel, s, s, cv::BORDER_REFLECT_101);
    cv::GaussianBlur(strip.data, blur_data, kernel, s, s, cv::BORDER_REFLECT_101);
    denominator = cv::max(blur_valid, 1e-6f);  // into its buffer
    // Van Cittert deconvolution: z <- z + (y - h * z), from z = y.
    y.copyTo(z);
    for (int n = 0; n < kIterations; ++n) {
      cv::multiply(z, valid, zv);
      cv::GaussianBlur(zv, blur_z, kernel, s, s, cv::BORDER_REFLECT_101);
      cv::divide(blur_z, denominator, blur_z);
      cv::subtract(y, blur_z, blur_z);
      cv::add(z, blur_z, z);
      // Water keeps its height.
      y.copyTo(z, water);
    }
    for (int row = r0; row < r1; ++row) {
      for (int col = 0; col < cols; ++col) {
        const size_t i = static_cast<size_t>(row) * cols + col;
        if (!std::isfinite(world->up_m[i]) || water.at<unsigned char>(row - a, col)) continue;
        // The land's share of the footprint's weight on data (geo::SharpenTerrain).
        const float w = blur_valid.at<float>(row - a, col);
        const float land_share = w / std::max(blur_data.at<float>(row - a, col), w + 1e-12f);
        // Tapered at the shore as the estimator's sharpening is: a footprint half over water sees
        // a bank's slope and not the land around it.
        change[i] = static_cast<float>(geo::ShoreTaper(land_share) * spec.gain *
                                       (z.at<float>(row - a, col) - y.at<float>(row - a, col)));
      }
    }
  }
  for (size_t i = 0; i < change.size(); ++i) world->up_m[i] += change[i];
}

}  // namespace skerry::sim
