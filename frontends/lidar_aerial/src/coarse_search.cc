#include "skerry/lidar_aerial/coarse_search.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace skerry::lidar_aerial {

namespace {

constexpr double kDeg = M_PI / 180.0;

// Vertex of the parabola through (-1, a), (0, b), (1, c), within [-0.5, 0.5].
double ParabolaPeak(double a, double b, double c) {
  const double d = a - 2.0 * b + c;
  if (!(d < 0.0)) return 0.0;
  return std::clamp(0.5 * (a - c) / d, -0.5, 0.5);
}

}  // namespace

CoarseMatch CoarseSearch(const AerialMap& map,
                         const std::vector<Eigen::Vector3d>& points_l,
                         const PlanarPose& prior,
                         const CoarseSearchOptions& o) {
  if (!(o.resolution_m > 0.0) || !(o.heading_step_deg > 0.0) || !(o.search_radius_m >= 0.0) ||
      !(o.heading_range_deg >= 0.0) || !(o.heading_range_deg <= 180.0)) {
    throw std::invalid_argument(
        "CoarseSearch: resolution and heading step must be positive, the search radius and "
        "heading range (at most 180 degrees) not negative");
  }
  CoarseMatch out;
  if (points_l.empty()) return out;
  // The coarse grid: a whole number of map cells per coarse cell, so that INTER_AREA averages
  // exact blocks and coarse cell centres are known exactly.
  const int f = std::max(1, static_cast<int>(std::lround(o.resolution_m / map.resolution_m())));
  const double res = f * map.resolution_m();
  cv::Mat density;
  map.edges().convertTo(density, CV_32F, 1.0 / 255.0);
  if (f > 1) {
    cv::resize(density, density, cv::Size(map.cols() / f, map.rows() / f), 0, 0, cv::INTER_AREA);
  }
  const double sigma = o.blur_m / res;
  if (sigma > 0.3) cv::GaussianBlur(density, density, cv::Size(), sigma);
  // Coarse cell (i, j) <-> map cell (f i + (f - 1) / 2, ...) <-> ENU.
  const auto coarse_to_enu = [&](double i, double j) {
    return map.ToEnu({f * i + 0.5 * (f - 1), f * j + 0.5 * (f - 1)});
  };
  const auto enu_to_coarse = [&](const Eigen::Vector2d& xy) -> Eigen::Vector2d {
    return (map.ToGrid(xy).array() - 0.5 * (f - 1)) / f;
  };

  const int radius_px = std::max(1, static_cast<int>(std::ceil(o.search_radius_m / res)));
  const int pad = static_cast<int>(std::ceil(3.0 * sigma)) + 1;
  // Headings on a fixed grid (multiples of the step) covering prior +- range: the same scene
  // gives the same sweep, and so the same match, whatever the prior's fraction of a step.
  const double step = o.heading_step_deg * kDeg;
  const int k_first = static_cast<int>(std::floor((prior.yaw - o.heading_range_deg * kDeg) / step));
  const int k_last = static_cast<int>(std::ceil((prior.yaw + o.heading_range_deg * kDeg) / step));
  const Eigen::Vector2d prior_px = enu_to_coarse(prior.t);
  const int pu = static_cast<int>(std::lround(prior_px.x()));
  const int pv = static_cast<int>(std::lround(prior_px.y()));

  struct Heading {
    double yaw;
    cv::Mat score;  // (2 radius + 1)^2: the sensor at prior_px + (u - radius, v - radius)
  };
  std::vector<Heading> sweep;
  for (int k = k_first; k <= k_last; ++k) {
    const double yaw = k * step;
    const Eigen::Matrix2d R = PlanarPose{Eigen::Vector2d::Zero(), yaw}.R();
    // Template: the rotated points around the sensor, in coarse pixels (column east, row south).
    Eigen::AlignedBox2d box;
    std::vector<Eigen::Vector2d> px(points_l.size());
    for (size_t n = 0; n < points_l.size(); ++n) {
      const Eigen::Vector2d q = R * points_l[n].head<2>();
      px[n] = Eigen::Vector2d(q.x() / res, -q.y() / res);
      box.extend(px[n]);
    }
    const int ox = pad - static_cast<int>(std::floor(box.min().x()));  // sensor's template pixel
    const int oy = pad - static_cast<int>(std::floor(box.min().y()));
    const int tw = static_cast<int>(std::ceil(box.max().x())) + ox + pad + 1;
    const int th = static_cast<int>(std::ceil(box.max().y())) + oy + pad + 1;
    cv::Mat tmpl = cv::Mat::zeros(th, tw, CV_32F);
    for (const Eigen::Vector2d& p : px) {  // bilinear splat
      const double x = p.x() + ox, y = p.y() + oy;
      const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
      const float a = static_cast<float>(x - x0), b = static_cast<float>(y - y0);
      tmpl.at<float>(y0, x0) += (1 - a) * (1 - b);
      tmpl.at<float>(y0, x0 + 1) += a * (1 - b);
      tmpl.at<float>(y0 + 1, x0) += (1 - a) * b;
      tmpl.at<float>(y0 + 1, x0 + 1) += a * b;
    }
    if (sigma > 0.3) cv::GaussianBlur(tmpl, tmpl, cv::Size(), sigma);
    // The map under every placement: template top-left at (pu - radius - ox, pv - radius - oy).
    const cv::Rect want(pu - radius_px - ox, pv - radius_px - oy, tw + 2 * radius_px,
                        th + 2 * radius_px);
    const cv::Rect have = want & cv::Rect(0, 0, density.cols, density.rows);
    if (have.empty()) return out;
    cv::Mat window = cv::Mat::zeros(want.size(), CV_32F);
    density(have).copyTo(
        window(cv::Rect(have.x - want.x, have.y - want.y, have.width, have.height)));
    Heading h{yaw, cv::Mat()};
    cv::matchTemplate(window, tmpl, h.score, cv::TM_CCOEFF_NORMED);
    cv::patchNaNs(h.score, -1.0);
    sweep.push_back(std::move(h));
  }
  out.headings = static_cast<int>(sweep.size());

  // The best placement over every heading.
  size_t kb = 0;
  cv::Point best(0, 0);
  double sb = -2.0;
  for (size_t k = 0; k < sweep.size(); ++k) {
    double mx;
    cv::Point at;
    cv::minMaxLoc(sweep[k].score, nullptr, &mx, nullptr, &at);
    if (mx > sb) {
      sb = mx;
      kb = k;
      best = at;
    }
  }
  const cv::Mat& S = sweep[kb].score;
  const auto s_at = [](const cv::Mat& m, int x, int y) {
    return static_cast<double>(m.at<float>(y, x));
  };
  double du = 0.0, dv = 0.0, dk = 0.0;
  if (best.x > 0 && best.x + 1 < S.cols) {
    du = ParabolaPeak(s_at(S, best.x - 1, best.y), sb, s_at(S, best.x + 1, best.y));
  }
  if (best.y > 0 && best.y + 1 < S.rows) {
    dv = ParabolaPeak(s_at(S, best.x, best.y - 1), sb, s_at(S, best.x, best.y + 1));
  }
  if (kb > 0 && kb + 1 < sweep.size()) {
    dk = ParabolaPeak(s_at(sweep[kb - 1].score, best.x, best.y), sb,
                      s_at(sweep[kb + 1].score, best.x, best.y));
  }
  const auto placement_enu = [&](double u, double v) {
    return coarse_to_enu(pu + (u - radius_px), pv + (v - radius_px));
  };
  // A map without edges under the window (a blank image, open water) correlates with nothing.
  if (!(sb > 0.0)) return out;
  out.valid = true;
  out.score = sb;
  out.pose.t = placement_enu(best.x + du, best.y + dv);
  out.pose.yaw = WrapAngle(sweep[kb].yaw + dk * o.heading_step_deg * kDeg);

  // Second-best score away from the best position; the spread of the peak.
  const double r2 = std::pow(o.ambiguity_radius_m / res, 2);
  const double level = sb - o.peak_drop;
  double second = -1.0, wsum = 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second_moment = Eigen::Matrix3d::Zero();
  for (const Heading& h : sweep) {
    for (int v = 0; v < h.score.rows; ++v) {
      const float* row = h.score.ptr<float>(v);
      for (int u = 0; u < h.score.cols; ++u) {
        const double s = row[u];
        const double d2 = std::pow(u - best.x, 2) + std::pow(v - best.y, 2);
        if (d2 > r2) second = std::max(second, s);
        if (s <= level) continue;
        const double w = s - level;
        const Eigen::Vector2d xy = placement_enu(u, v) - out.pose.t;  // about the match
        const Eigen::Vector3d x(xy.x(), xy.y(), WrapAngle(h.yaw - out.pose.yaw));
        wsum += w;
        mean += w * x;
        second_moment += w * x * x.transpose();
      }
    }
  }
  mean /= wsum;
  out.covariance = second_moment / wsum - mean * mean.transpose();
  out.covariance(0, 0) += res * res / 12.0;
  out.covariance(1, 1) += res * res / 12.0;
  out.covariance(2, 2) += std::pow(o.heading_step_deg * kDeg, 2) / 12.0;
  out.second_score = second;
  out.ambiguity = sb > 0.0 ? std::max(0.0, second) / sb : 1.0;
  out.ambiguous = out.ambiguity >= o.ambiguous_ratio;
  return out;
}

}  // namespace skerry::lidar_aerial
