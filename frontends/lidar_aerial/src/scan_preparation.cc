#include "skerry/lidar_aerial/scan_preparation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "skerry/lidar_aerial/quantile_canny.h"

namespace skerry::lidar_aerial {

namespace {

struct Column {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();  // levelled frame
  double time_sum = 0.0;                          // of its returns' times
  std::vector<float> z;                           // heights of its returns
  int count = 0;
  float top_z = -std::numeric_limits<float>::infinity();  // the highest return
  float top_intensity = 0.0f;                             // its intensity
  bool front = false;  // holds the nearest return of an azimuth sector
};

// The returns span min_extent with no gap wider than max_gap (z sorted in place).
bool IsWall(std::vector<float>* z, double min_extent, double max_gap) {
  // (max_gap: the caller's, grown with range for a scanner's beam spacing.)
  if (z->size() < 2) return false;
  std::sort(z->begin(), z->end());
  if (z->back() - z->front() < min_extent) return false;
  for (size_t k = 1; k < z->size(); ++k) {
    if ((*z)[k] - (*z)[k - 1] > max_gap) return false;
  }
  return true;
}

}  // namespace

PreparedScan PrepareScan(const std::vector<Eigen::Vector3d>& points_s,
                         const std::vector<float>& intensity,
                         const Eigen::Quaterniond& q_level_s,
                         const ScanPreparationOptions& o,
                         const std::vector<double>& time_s) {
  if (!(o.cell_m > 0.0)) throw std::invalid_argument("PrepareScan: cell_m must be positive");
  if (!intensity.empty() && intensity.size() != points_s.size()) {
    throw std::invalid_argument("PrepareScan: one intensity per point, or none");
  }
  if (!time_s.empty() && time_s.size() != points_s.size()) {
    throw std::invalid_argument("PrepareScan: one time per point, or none");
  }
  const bool with_time = !time_s.empty();
  const bool with_intensity = o.intensity_edges && !intensity.empty();
  PreparedScan out;
  out.input = static_cast<int>(points_s.size());
  const Eigen::Matrix3d R = q_level_s.normalized().toRotationMatrix();
  std::vector<Eigen::Vector3d> kept_l;
  std::vector<float> kept_i;
  std::vector<double> kept_t;
  kept_l.reserve(points_s.size());
  Eigen::AlignedBox2d box;
  const bool hull = !o.hull_s.isEmpty();
  for (size_t n = 0; n < points_s.size(); ++n) {
    const Eigen::Vector3d& p = points_s[n];
    if (!p.allFinite() || (with_intensity && !std::isfinite(intensity[n])) ||
        (with_time && !std::isfinite(time_s[n]))) {
      ++out.dropped_invalid;
      continue;
    }
    if (hull && o.hull_s.contains(p)) {
      ++out.dropped_hull;
      continue;
    }
    const Eigen::Vector3d l = R * p;
    const double range = l.head<2>().norm();
    if (range < o.min_range_m || (o.max_range_m > 0.0 && range > o.max_range_m)) {
      ++out.dropped_range;
      continue;
    }
    if (l.z() < o.min_height_m) {
      ++out.dropped_low;
      continue;
    }
    kept_l.push_back(l);
    if (with_intensity) kept_i.push_back(intensity[n]);
    if (with_time) kept_t.push_back(time_s[n]);
    box.extend(l.head<2>().eval());
  }
  if (kept_l.empty()) return out;

  // A dense grid of columns over the returns' box, one cell of margin.
  const Eigen::Vector2d origin = box.min() - Eigen::Vector2d::Constant(o.cell_m);
  // (Sizes in double first: a stray return kilometres away must be an error, not an overflow.)
  const double nxd = std::floor(box.sizes().x() / o.cell_m) + 3.0;
  const double nyd = std::floor(box.sizes().y() / o.cell_m) + 3.0;
  if (nxd * nyd > 64e6) {
    throw std::invalid_argument("PrepareScan: the scan spans more than 64 million columns of " +
                                std::to_string(o.cell_m) + " m (returns far out of range?)");
  }
  const int nx = static_cast<int>(nxd);
  const int ny = static_cast<int>(nyd);
  std::vector<Column> grid(static_cast<size_t>(nx) * static_cast<size_t>(ny));
  const auto at = [nx](int i, int j) { return static_cast<size_t>(j) * nx + i; };
  for (size_t n = 0; n < kept_l.size(); ++n) {
    const Eigen::Vector3d& l = kept_l[n];
    const int i = static_cast<int>((l.x() - origin.x()) / o.cell_m);
    const int j = static_cast<int>((l.y() - origin.y()) / o.cell_m);
    Column& c = grid[at(i, j)];
    c.sum += l;
    if (with_time) c.time_sum += kept_t[n];
    if (static_cast<float>(l.z()) > c.top_z) {
      c.top_z = static_cast<float>(l.z());
      if (with_intensity) c.top_intensity = kept_i[n];
    }
    c.z.push_back(static_cast<float>(l.z()));
    ++c.count;
  }
  // The front: per azimuth sector about the sensor, the column of the nearest return (what a
  // vessel's LiDAR sees first across the water: a quay's or a pier's edge, a hull).
  if (o.front_edges && o.front_sector_deg > 0.0) {
    const int sectors = static_cast<int>(std::ceil(360.0 / o.front_sector_deg));
    std::vector<double> nearest(static_cast<size_t>(sectors), HUGE_VAL);
    std::vector<size_t> which(static_cast<size_t>(sectors), 0);
    for (size_t n = 0; n < kept_l.size(); ++n) {
      const Eigen::Vector3d& l = kept_l[n];
      const double r = l.head<2>().norm();
      double az = std::atan2(l.y(), l.x()) * 180.0 / M_PI + 180.0;
      const int k = std::min(sectors - 1, static_cast<int>(az / o.front_sector_deg));
      if (r < nearest[static_cast<size_t>(k)]) {
        nearest[static_cast<size_t>(k)] = r;
        which[static_cast<size_t>(k)] = n;
      }
    }
    for (int k = 0; k < sectors; ++k) {
      if (!std::isfinite(nearest[static_cast<size_t>(k)])) continue;
      const Eigen::Vector3d& l = kept_l[which[static_cast<size_t>(k)]];
      const int i = static_cast<int>((l.x() - origin.x()) / o.cell_m);
      const int j = static_cast<int>((l.y() - origin.y()) / o.cell_m);
      grid[at(i, j)].front = true;
    }
  }
  // Highest return per column; holes with enough neighbours take their neighbours' highest.
  const float kNone = -std::numeric_limits<float>::infinity();
  std::vector<float> top(grid.size(), kNone);
  for (size_t k = 0; k < grid.size(); ++k) {
    if (grid[k].count > 0) top[k] = grid[k].top_z;
  }
  // The top surface's intensity image (row 0 north) and where it is observed.
  cv::Mat seen = cv::Mat::zeros(ny, nx, CV_8UC1);
  cv::Mat shade = cv::Mat::zeros(ny, nx, CV_32FC1);
  std::vector<float> surface = top;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const Column& c = grid[at(i, j)];
      if (c.count > 0) {
        seen.at<std::uint8_t>(ny - 1 - j, i) = 255;
        shade.at<float>(ny - 1 - j, i) = c.top_intensity;
        continue;
      }
      if (i == 0 || j == 0 || i + 1 == nx || j + 1 == ny) continue;
      int n = 0;
      float high = kNone, sum = 0.0f;
      for (int dj = -1; dj <= 1; ++dj) {
        for (int di = -1; di <= 1; ++di) {
          const size_t k = at(i + di, j + dj);
          if (top[k] == kNone) continue;
          ++n;
          high = std::max(high, top[k]);
          sum += grid[k].top_intensity;
        }
      }
      if (n < o.fill_neighbours) continue;
      surface[at(i, j)] = high;
      seen.at<std::uint8_t>(ny - 1 - j, i) = 255;
      shade.at<float>(ny - 1 - j, i) = sum / static_cast<float>(n);
    }
  }

  // The local floor: the lowest return within floor_radius_m (a min filter over the columns'
  // lowest returns; columns without returns do not take part).
  cv::Mat bottom(ny, nx, CV_32FC1, cv::Scalar(std::numeric_limits<float>::infinity()));
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const Column& c = grid[at(i, j)];
      if (c.count > 0) bottom.at<float>(ny - 1 - j, i) = *std::min_element(c.z.begin(), c.z.end());
    }
  }
  const int floor_cells = std::max(1, static_cast<int>(std::lround(o.floor_radius_m / o.cell_m)));
  cv::Mat floor_z;
  cv::erode(bottom, floor_z,
            cv::getStructuringElement(cv::MORPH_ELLIPSE,
                                      cv::Size(2 * floor_cells + 1, 2 * floor_cells + 1)),
            cv::Point(-1, -1), 1, cv::BORDER_CONSTANT,
            cv::Scalar(std::numeric_limits<float>::infinity()));

  // Near what stands high (within the intensity edges' blur), the top surface's intensity edges
  // are a high thing's outline at its foot: in the image that outline is displaced with the
  // thing's top, and shadowed.
  cv::Mat high = cv::Mat::zeros(ny, nx, CV_8UC1);
  if (o.max_edge_height_m > 0.0) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const float t = surface[at(i, j)];
        high.at<std::uint8_t>(ny - 1 - j, i) =
            t != kNone && t - floor_z.at<float>(ny - 1 - j, i) > o.max_edge_height_m ? 255 : 0;
      }
    }
    const int r = static_cast<int>(std::ceil(2.0 * o.intensity_blur_m / o.cell_m)) + 1;
    cv::dilate(high, high,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1)));
  }

  struct Kept {
    Eigen::Vector3d mean_l;
    double rank;  // larger first
    double time;  // mean time of its returns
    float top;    // the column's highest return
    float floor;  // the local floor there
  };
  std::vector<Kept> kept, kept_shade;
  cv::Mat shade_edges;
  if (with_intensity) {
    shade_edges = QuantileCanny(
        shade, seen, {o.intensity_blur_m / o.cell_m, o.canny_high_quantile, o.canny_low_quantile});
  }
  for (int j = 1; j + 1 < ny; ++j) {
    for (int i = 1; i + 1 < nx; ++i) {
      Column& c = grid[at(i, j)];
      if (c.count == 0) continue;
      ++out.columns;
      const float t = top[at(i, j)];
      bool rim = false;
      for (int dj = -1; dj <= 1 && !rim; ++dj) {
        for (int di = -1; di <= 1 && !rim; ++di) {
          const float s = surface[at(i + di, j + dj)];
          rim = s != kNone && t - s >= o.min_vertical_extent_m;
        }
      }
      const double range =
          (origin + Eigen::Vector2d(i + 0.5, j + 0.5) * o.cell_m).norm();  // from the sensor
      const bool wall = IsWall(&c.z, o.min_vertical_extent_m,
                               std::max(o.max_wall_gap_m, o.max_wall_gap_per_m * range));
      const bool front = c.front && !wall && !rim;
      const bool low =
          o.max_edge_height_m <= 0.0 || t - floor_z.at<float>(ny - 1 - j, i) <= o.max_edge_height_m;
      out.wall_columns += wall;
      out.rim_columns += rim && !wall && low;
      out.front_columns += front && low;
      out.dropped_high += !wall && !low;
      if (!wall && !low) continue;
      const Kept k{c.sum / c.count, static_cast<double>(c.count), c.time_sum / c.count, t,
                   std::min(floor_z.at<float>(ny - 1 - j, i), t)};
      if (wall || rim || front) {
        kept.push_back(k);
      } else if (with_intensity && shade_edges.at<std::uint8_t>(ny - 1 - j, i) != 0 &&
                 high.at<std::uint8_t>(ny - 1 - j, i) == 0) {
        ++out.intensity_columns;
        kept_shade.push_back(k);
      }
    }
  }
  // The fullest columns first; ties by position (the grid's order is already deterministic).
  const auto fuller = [](const Kept& a, const Kept& b) { return a.rank > b.rank; };
  std::stable_sort(kept.begin(), kept.end(), fuller);
  std::stable_sort(kept_shade.begin(), kept_shade.end(), fuller);
  if (o.max_points > 0) {
    const std::ptrdiff_t cap = o.max_points;
    const std::ptrdiff_t n_structure = static_cast<std::ptrdiff_t>(kept.size());
    const std::ptrdiff_t n_shade = static_cast<std::ptrdiff_t>(kept_shade.size());
    const std::ptrdiff_t structure =
        std::min(n_structure, std::max(cap - n_shade, n_shade > 0 ? cap / 2 : cap));
    kept.resize(static_cast<size_t>(structure));
    kept_shade.resize(static_cast<size_t>(std::min(n_shade, cap - structure)));
  }
  kept.insert(kept.end(), kept_shade.begin(), kept_shade.end());
  const Eigen::Matrix3d Rt = R.transpose();
  out.points_s.reserve(kept.size());
  out.returns.reserve(kept.size());
  for (const Kept& k : kept) {
    out.points_s.push_back(Rt * k.mean_l);
    out.returns.push_back(static_cast<int>(k.rank));
    if (with_time) out.time_s.push_back(k.time);
    const float z = static_cast<float>(k.mean_l.z());
    out.top_m.push_back(std::max(0.0f, k.top - z));
    out.floor_m.push_back(std::min(0.0f, k.floor - z));
  }
  return out;
}

}  // namespace skerry::lidar_aerial
