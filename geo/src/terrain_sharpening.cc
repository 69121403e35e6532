#include "skerry/geo/terrain_sharpening.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "skerry/geo/footprint_strip.h"

namespace skerry::geo {

double ShoreTaper(double land_share) { return std::clamp((land_share - 0.9) / 0.1, 0.0, 1.0); }

void SharpenTerrain(const TerrainSharpening& sharpening,
                    double earth_radius_m,
                    EnuHeightGrid* grid) {
  const double g = sharpening.gain, sigma = sharpening.footprint_sigma_m;
  if (!(g >= 0.0) || !std::isfinite(g)) {
    throw std::invalid_argument("SharpenTerrain: gain must be >= 0");
  }
  if (g == 0.0 || grid->cols < 1 || grid->rows < 1) return;
  if (!(sigma > 0.0) || !std::isfinite(sigma)) {
    throw std::invalid_argument("SharpenTerrain: footprint_sigma_m must be > 0");
  }
  const int cols = grid->cols, rows = grid->rows;
  const double s = sigma / grid->spacing_m;  // in nodes
  const int half = FootprintHalfWidth(s, cols, rows);
  const cv::Size kernel(2 * half + 1, 2 * half + 1);
  // The change of every node, from the grid as it was: applied once all strips are done.
  std::vector<float> change(grid->up_m.size(), 0.0f);
  cv::Mat blur_z, blur_valid, blur_data;  // reused by strips of one size
  for (int r0 = 0; r0 < rows; r0 += kFootprintStripRows) {
    const int r1 = std::min(rows, r0 + kFootprintStripRows);
    // The strip and `half` rows around it; the blur reflects at the grid's own edges only.
    const int a = std::max(0, r0 - half), b = std::min(rows, r1 + half);
    FootprintStrip strip = ReadFootprintStrip(*grid, a, b, earth_radius_m);
    if (!strip.has_data) continue;
    // Normalised convolution: the blur of the heights where they hold data over the blur of
    // the mask, so a void does not pull its neighbours towards 0. Water (level over its 3 x 3
    // nodes) is no part of the land's footprint: a DEM's lakes and sea are set flat by hand
    // (SRTM's water body data), and with them in its mean a node on the shore would rise above
    // the land behind it, a wall along every shore.
    const cv::Mat& valid = strip.land;
    const cv::Mat& water = strip.water;
    const double ref = strip.ref_m;
    cv::Mat& z = strip.up;
    cv::multiply(z, valid, z);  // in place: the land's heights
    // Blurring the strip and its halo as one image reflects at the halo's outer rows where the
    // strip is not at the grid's edge; those rows are `half` (4 sigma) away from any row kept.
    cv::GaussianBlur(z, blur_z, kernel, s, s, cv::BORDER_REFLECT_101);
    cv::GaussianBlur(valid, blur_valid, kernel, s, s, cv::BORDER_REFLECT_101);
    cv::GaussianBlur(strip.data, blur_data, kernel, s, s, cv::BORDER_REFLECT_101);
    for (int row = r0; row < r1; ++row) {
      for (int col = 0; col < cols; ++col) {
        const size_t i = static_cast<size_t>(row) * cols + col;
        const float w = blur_valid.at<float>(row - a, col);
        // Water has no footprint to undo.
        if (!std::isfinite(grid->up_m[i]) || !(w > 0.0f) || water.at<unsigned char>(row - a, col)) {
          continue;
        }
        const double mean = blur_z.at<float>(row - a, col) / w + ref;
        // The land's share of the footprint's weight on data: water, not a void, tapers.
        const double land_share = w / std::max(blur_data.at<float>(row - a, col), w);
        change[i] = static_cast<float>(ShoreTaper(land_share) * g * (grid->up_m[i] - mean));
      }
    }
  }
  for (size_t i = 0; i < change.size(); ++i) grid->up_m[i] += change[i];
}

}  // namespace skerry::geo
