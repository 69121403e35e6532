#include "skerry/lidar_aerial/baseline_pso_matcher.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/core.hpp>
#include <random>
#include <stdexcept>
#include <utility>

namespace skerry::lidar_aerial::baseline {

namespace {

constexpr double kDeg = M_PI / 180.0;

using Cell = std::pair<int, int>;

Cell CellOf(const Eigen::Vector2d& p, double size) {
  return {static_cast<int>(std::floor(p.x() / size)), static_cast<int>(std::floor(p.y() / size))};
}

// Steps 2 and 3, in the levelled frame (heading-free): the centres of the fullest cells, then per
// RANSAC cell the inliers of its best line.
std::vector<Eigen::Vector2d> StackedLinePoints(const std::vector<Eigen::Vector3d>& points_l,
                                               const BaselineOptions& o) {
  std::map<Cell, int> counts;
  for (const Eigen::Vector3d& p : points_l) {
    if (p.allFinite()) ++counts[CellOf(p.head<2>(), o.cell_m)];
  }
  std::vector<std::pair<int, Cell>> ranked;
  for (const auto& [cell, n] : counts) ranked.emplace_back(n, cell);
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  if (static_cast<int>(ranked.size()) > o.stacked_cells) ranked.resize(o.stacked_cells);
  std::map<Cell, std::vector<Eigen::Vector2d>> by_ransac_cell;
  for (const auto& [n, cell] : ranked) {
    const Eigen::Vector2d c((cell.first + 0.5) * o.cell_m, (cell.second + 0.5) * o.cell_m);
    by_ransac_cell[CellOf(c, o.ransac_cell_m)].push_back(c);
  }
  std::mt19937 rng(o.seed);
  std::vector<Eigen::Vector2d> kept;
  for (const auto& [cell, pts] : by_ransac_cell) {
    if (static_cast<int>(pts.size()) < o.ransac_min_inliers) continue;
    std::uniform_int_distribution<size_t> pick(0, pts.size() - 1);
    std::vector<size_t> best;
    for (int it = 0; it < o.ransac_iterations; ++it) {
      const Eigen::Vector2d a = pts[pick(rng)], b = pts[pick(rng)];
      const Eigen::Vector2d d = b - a;
      if (d.norm() < 1e-9) continue;
      const Eigen::Vector2d n = Eigen::Vector2d(-d.y(), d.x()).normalized();
      std::vector<size_t> in;
      for (size_t k = 0; k < pts.size(); ++k) {
        if (std::abs(n.dot(pts[k] - a)) <= o.ransac_inlier_m) in.push_back(k);
      }
      if (in.size() > best.size()) best = std::move(in);
    }
    if (static_cast<int>(best.size()) < o.ransac_min_inliers) continue;
    for (size_t k : best) kept.push_back(pts[k]);
  }
  return kept;
}

}  // namespace

BaselineMatch MatchBaseline(const AerialMap& map,
                            const std::vector<Eigen::Vector3d>& points_l,
                            const PlanarPose& prior,
                            const BaselineOptions& o) {
  if (std::abs(map.resolution_m() - o.cell_m) > 1e-9 * o.cell_m) {
    throw std::invalid_argument("MatchBaseline: the map's cell must be the baseline's cell_m");
  }
  BaselineMatch out;
  out.pose = prior;
  out.matched = prior;
  const std::vector<Eigen::Vector2d> pts = StackedLinePoints(points_l, o);
  if (pts.empty()) return out;

  // Step 4: the map's edges on the tile centred on the prior.
  const int n = static_cast<int>(std::lround(o.tile_m / o.cell_m));
  const Eigen::Vector2d centre = map.ToGrid(prior.t);
  const int c0 = static_cast<int>(std::lround(centre.x())) - n / 2;
  const int r0 = static_cast<int>(std::lround(centre.y())) - n / 2;
  const cv::Rect want(c0, r0, n, n);
  const cv::Rect have = want & cv::Rect(0, 0, map.cols(), map.rows());
  if (have.empty()) return out;
  cv::Mat tile = cv::Mat::zeros(n, n, CV_32F);
  map.edges()(have).convertTo(tile(cv::Rect(have.x - c0, have.y - r0, have.width, have.height)),
                              CV_32F, 1.0 / 255.0);
  const double tile_norm = cv::norm(tile);
  if (!(tile_norm > 0.0)) return out;
  cv::Mat tile_f;
  cv::dft(tile, tile_f, cv::DFT_COMPLEX_OUTPUT);
  // The prior's position in tile pixels (sub-cell: where the scan's origin is drawn).
  const Eigen::Vector2d origin = centre - Eigen::Vector2d(c0, r0);

  // Step 5 at one heading: the peak of the circular correlation and the shift it says.
  struct Fit {
    double score = -1.0;
    Eigen::Vector2d shift_m = Eigen::Vector2d::Zero();
  };
  const auto fit = [&](double yaw) {
    ++out.evaluations;
    Fit f;
    const Eigen::Matrix2d R = PlanarPose{Eigen::Vector2d::Zero(), yaw}.R();
    cv::Mat scan = cv::Mat::zeros(n, n, CV_32F);
    for (const Eigen::Vector2d& p : pts) {
      const Eigen::Vector2d w = R * p;
      const int u = static_cast<int>(std::lround(origin.x() + w.x() / o.cell_m));
      const int v = static_cast<int>(std::lround(origin.y() - w.y() / o.cell_m));
      if (u >= 0 && v >= 0 && u < n && v < n) scan.at<float>(v, u) = 1.0f;
    }
    const double scan_norm = cv::norm(scan);
    if (!(scan_norm > 0.0)) return f;
    cv::Mat scan_f, product, corr;
    cv::dft(scan, scan_f, cv::DFT_COMPLEX_OUTPUT);
    cv::mulSpectrums(tile_f, scan_f, product, 0, /*conjB=*/true);
    cv::idft(product, corr, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
    double peak;
    cv::Point at;
    cv::minMaxLoc(corr, nullptr, &peak, nullptr, &at);
    // corr(dy, dx) = sum tile(y + dy, x + dx) scan(y, x): the scan moves by (dx, dy), wrapped.
    const int dx = at.x > n / 2 ? at.x - n : at.x;
    const int dy = at.y > n / 2 ? at.y - n : at.y;
    f.score = peak / (tile_norm * scan_norm);
    f.shift_m = Eigen::Vector2d(dx * o.cell_m, -dy * o.cell_m);
    return f;
  };

  // Step 6: the swarm over heading.
  const double lo = prior.yaw - o.heading_range_deg * kDeg;
  const double hi = prior.yaw + o.heading_range_deg * kDeg;
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int m = std::max(1, o.particles);
  std::vector<double> x(m), v(m), best_x(m);
  std::vector<Fit> best_f(m);
  double g_x = prior.yaw;
  Fit g_f;
  for (int i = 0; i < m; ++i) {
    x[i] = lo + (hi - lo) * unit(rng);
    v[i] = (hi - lo) * (unit(rng) - 0.5) * 0.5;
    best_x[i] = x[i];
    best_f[i] = fit(x[i]);
    if (best_f[i].score > g_f.score) {
      g_f = best_f[i];
      g_x = x[i];
    }
  }
  for (int it = 0; it < o.iterations; ++it) {
    for (int i = 0; i < m; ++i) {
      v[i] = 0.7 * v[i] + 1.5 * unit(rng) * (best_x[i] - x[i]) + 1.5 * unit(rng) * (g_x - x[i]);
      x[i] = std::clamp(x[i] + v[i], lo, hi);
      const Fit f = fit(x[i]);
      if (f.score > best_f[i].score) {
        best_f[i] = f;
        best_x[i] = x[i];
      }
      if (f.score > g_f.score) {
        g_f = f;
        g_x = x[i];
      }
    }
  }
  if (!(g_f.score > 0.0)) return out;
  out.valid = true;
  out.score = g_f.score;
  out.matched = {prior.t + g_f.shift_m, WrapAngle(g_x)};
  // Step 7: the gate.
  out.gated = g_f.shift_m.norm() > o.gate_m;
  if (!out.gated) out.pose = out.matched;
  return out;
}

}  // namespace skerry::lidar_aerial::baseline
