#include "skerry/skyline/baseline_grid_search.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

namespace skerry::skyline::baseline {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Prior work's ray trace of one azimuth: fixed steps, bilinear heights, highest elevation; the
// terrain point at that step.
bool TraceColumn(const geo::EnuHeightGrid& grid,
                 const Eigen::Vector3d& p,
                 double azimuth,
                 const BaselineOptions& o,
                 Eigen::Vector3d* point) {
  const double dx = std::sin(azimuth), dy = std::cos(azimuth);
  const double kappa = o.refraction_k / (2.0 * 6371000.0);
  double best = -kPi;
  bool found = false;
  for (double s = o.min_range_m; s <= o.max_range_m; s += o.march_step_m) {
    const auto z = grid.UpAt(p.x() + s * dx, p.y() + s * dy);
    if (!z) continue;
    const double e = std::atan2(*z - p.z(), s) + kappa * s;
    if (e > best) {
      best = e;
      // The point that appears at that elevation: the terrain point, raised by the refraction
      // bend so that projecting it gives the apparent direction.
      *point = Eigen::Vector3d(p.x() + s * dx, p.y() + s * dy, *z + kappa * s * s);
      found = true;
    }
  }
  return found;
}

Eigen::Matrix3d Attitude(const Eigen::Matrix3d& r_level_c, double heading) {
  return Eigen::AngleAxisd(-heading, Eigen::Vector3d::UnitZ()).toRotationMatrix() * r_level_c;
}

double PathHeading(const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  const Eigen::Vector2d d = to - from;
  return std::atan2(d.x(), d.y());
}

}  // namespace

std::vector<int> MorphologicalSkyline(const cv::Mat& mask, int morphology_px) {
  cv::Mat sky;
  cv::threshold(mask, sky, 127, 255, cv::THRESH_BINARY);
  if (morphology_px > 1) {
    const cv::Mat k =
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(morphology_px, morphology_px));
    cv::morphologyEx(sky, sky, cv::MORPH_OPEN, k);
    cv::morphologyEx(sky, sky, cv::MORPH_CLOSE, k);
  }
  std::vector<int> rows(mask.cols, -1);
  for (int u = 0; u < mask.cols; ++u) {
    if (sky.at<uchar>(0, u) == 0) continue;
    for (int r = 1; r < mask.rows; ++r) {
      if (sky.at<uchar>(r, u) == 0) {
        rows[u] = r;
        break;
      }
    }
  }
  return rows;
}

std::vector<int> Hilltops(const std::vector<double>& rows,
                          double min_height_px,
                          double min_width_px) {
  const int n = static_cast<int>(rows.size());
  std::vector<int> peaks;
  const auto valid = [&](int u) { return u >= 0 && u < n && rows[u] >= 0; };
  for (int u = 1; u + 1 < n; ++u) {
    if (!valid(u) || !valid(u - 1) || !valid(u + 1)) continue;
    // A peak: the highest point (smallest row) of a plateau, taken at the plateau's middle.
    if (!(rows[u] <= rows[u - 1] && rows[u] <= rows[u + 1])) continue;
    int a = u, b = u;
    while (valid(a - 1) && rows[a - 1] == rows[u]) --a;
    while (valid(b + 1) && rows[b + 1] == rows[u]) ++b;
    if ((a + b) / 2 != u) continue;
    if (!valid(a - 1) || !valid(b + 1) || rows[a - 1] < rows[u] || rows[b + 1] < rows[u]) continue;
    // Its feet: walk down each side while the skyline keeps falling (rows growing), across the
    // steps of integer rows but not along a flat of more than 3 columns.
    const auto walk = [&](int u0, int dir) {
      int u = u0, flat = 0;
      while (valid(u + dir) && rows[u + dir] >= rows[u]) {
        flat = rows[u + dir] == rows[u] ? flat + 1 : 0;
        if (flat > 3) break;
        u += dir;
      }
      return u - dir * std::min(flat, 3);
    };
    const int l = walk(a, -1), r = walk(b, +1);
    const double height = std::min(rows[l], rows[r]) - rows[u];
    const double width = r - l;
    if (height > min_height_px && width > min_width_px) peaks.push_back(u);
  }
  return peaks;
}

int SadShift(const std::vector<double>& expected,
             const std::vector<double>& observed,
             int centre,
             int half_window,
             int max_shift,
             double* mean_abs) {
  const int n = static_cast<int>(expected.size());
  double best = std::numeric_limits<double>::infinity();
  int arg = 0;
  for (int d = -max_shift; d <= max_shift; ++d) {
    double me = 0, mo = 0;
    int count = 0;
    for (int k = -half_window; k <= half_window; ++k) {
      const int ue = centre + k, uo = centre + k + d;
      if (ue < 0 || ue >= n || uo < 0 || uo >= n || expected[ue] < 0 || observed[uo] < 0) continue;
      me += expected[ue];
      mo += observed[uo];
      ++count;
    }
    if (count < half_window) continue;  // at least half the window seen in both
    me /= count;
    mo /= count;
    double sad = 0;
    for (int k = -half_window; k <= half_window; ++k) {
      const int ue = centre + k, uo = centre + k + d;
      if (ue < 0 || ue >= n || uo < 0 || uo >= n || expected[ue] < 0 || observed[uo] < 0) continue;
      sad += std::abs((expected[ue] - me) - (observed[uo] - mo));
    }
    sad /= count;
    if (sad < best) {
      best = sad;
      arg = d;
    }
  }
  if (mean_abs) *mean_abs = best;
  return arg;
}

BaselineResult LocateFrameBaseline(const geo::EnuHeightGrid& grid,
                                   const CameraModel& camera,
                                   const cv::Mat& mask,
                                   const BaselineInput& in,
                                   const BaselineOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  BaselineResult out;
  out.xy = in.intended_xy;
  out.heading_rad = PathHeading(in.previous_xy, in.intended_xy);
  const auto finish = [&](const std::string& reason) {
    out.reason = reason;
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
  };
  if (mask.empty() || mask.type() != CV_8UC1 || mask.cols != camera.width() ||
      mask.rows != camera.height()) {
    return finish("the mask is not an 8-bit image of the camera's size");
  }
  // 1. Observed skyline.
  const std::vector<int> observed_int = MorphologicalSkyline(mask, o.morphology_px);
  std::vector<double> observed(observed_int.begin(), observed_int.end());
  // 2. Expected skyline and its 3-D points at the waypoint.
  const Eigen::Vector3d p0(in.intended_xy.x(), in.intended_xy.y(), in.camera_z);
  const Eigen::Matrix3d r0 = Attitude(in.r_level_c, out.heading_rad);
  const int w = camera.width();
  std::vector<double> expected(w, -1.0);
  std::vector<Eigen::Vector3d> points(w, Eigen::Vector3d::Zero());
  for (int u = 0; u < w; ++u) {
    const auto ray = camera.Ray({double(u), camera.cy()});
    if (!ray) continue;
    const Eigen::Vector3d d = r0 * *ray;
    Eigen::Vector3d x;
    if (!TraceColumn(grid, p0, std::atan2(d.x(), d.y()), o, &x)) continue;
    const auto px = camera.Project(r0.transpose() * (x - p0));
    if (!px || px->y() < 0 || px->y() >= camera.height()) continue;
    expected[u] = px->y();
    points[u] = x;
  }
  // 3. Hilltops.
  const std::vector<int> he = Hilltops(expected, o.min_hilltop_height_px, o.min_hilltop_width_px);
  const std::vector<int> ho = Hilltops(observed, o.min_hilltop_height_px, o.min_hilltop_width_px);
  out.hilltops_expected = static_cast<int>(he.size());
  out.hilltops_observed = static_cast<int>(ho.size());
  // 4. SAD matches: expected hilltop -> observed hilltop pixel.
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector2d>> matches;
  for (int ue : he) {
    double mean_abs = 0;
    const int d =
        SadShift(expected, observed, ue, o.sad_half_window_px, o.sad_max_shift_px, &mean_abs);
    if (!(mean_abs < o.sad_max_mean_px)) continue;
    int best = -1;
    double best_dist = o.peak_tolerance_px;
    for (int uo : ho) {
      const double dist = std::abs(uo - (ue + d));
      if (dist <= best_dist) {
        best_dist = dist;
        best = uo;
      }
    }
    if (best < 0) continue;
    matches.push_back({points[ue], Eigen::Vector2d(best, observed[best])});
  }
  out.matches = static_cast<int>(matches.size());
  if (out.matches < o.min_matches)
    return finish("failed match: " + std::to_string(out.matches) + " hilltop matches");
  // 5. Adaptive grid search over (x, y), heading implied by the path.
  const auto score = [&](const Eigen::Vector2d& xy) {
    const double heading = PathHeading(in.previous_xy, xy);
    const Eigen::Matrix3d r = Attitude(in.r_level_c, heading);
    const Eigen::Vector3d p(xy.x(), xy.y(), in.camera_z);
    double sum = 0;
    for (const auto& [x, px] : matches) {
      const auto q = camera.Project(r.transpose() * (x - p));
      sum += q ? (*q - px).norm() : 1e3;
    }
    return sum / matches.size();
  };
  Eigen::Vector2d centre = in.intended_xy;
  double best_score = score(centre);
  for (double h = o.start_half_width_m; h >= o.stop_half_width_m; h *= 0.5) {
    Eigen::Vector2d best_xy = centre;
    const int k = o.grid_points / 2;
    for (int i = -k; i <= k; ++i) {
      for (int j = -k; j <= k; ++j) {
        const Eigen::Vector2d xy = centre + Eigen::Vector2d(i, j) * (h / std::max(k, 1));
        const double s = score(xy);
        if (s < best_score) {
          best_score = s;
          best_xy = xy;
        }
      }
    }
    centre = best_xy;
  }
  out.ok = true;
  out.xy = centre;
  out.heading_rad = PathHeading(in.previous_xy, centre);
  out.reprojection_px = best_score;
  return finish("");
}

}  // namespace skerry::skyline::baseline
