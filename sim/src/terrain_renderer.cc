#include "skerry/sim/terrain_renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <random>
#include <stdexcept>

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

double WrapPi(double a) { return std::remainder(a, 2.0 * kPi); }

}  // namespace

TerrainRenderer::TerrainRenderer(geo::EnuHeightGrid grid, const TerrainRenderOptions& options)
    : grid_(std::move(grid)), options_(options) {
  if (grid_.cols < 2 || grid_.rows < 2 || !(grid_.spacing_m > 0.0)) {
    throw std::invalid_argument("TerrainRenderer: the height grid must be at least 2x2 nodes");
  }
  options_.sun_w.normalize();
}

bool TerrainRenderer::Height(double x, double y, double* z, Eigen::Vector2d* gradient) const {
  const double c = (x - grid_.origin_w.x()) / grid_.spacing_m;
  const double r = (y - grid_.origin_w.y()) / grid_.spacing_m;
  if (!(c >= 0.0 && r >= 0.0 && c <= grid_.cols - 1 && r <= grid_.rows - 1)) return false;
  const int c0 = std::min(static_cast<int>(c), grid_.cols - 2);
  const int r0 = std::min(static_cast<int>(r), grid_.rows - 2);
  const double tc = c - c0, tr = r - r0;
  const double a = grid_.at(c0, r0), b = grid_.at(c0 + 1, r0), d = grid_.at(c0, r0 + 1),
               e = grid_.at(c0 + 1, r0 + 1);
  const double v = (1 - tr) * ((1 - tc) * a + tc * b) + tr * ((1 - tc) * d + tc * e);
  if (std::isnan(v)) return false;
  *z = v;
  if (gradient) {
    (*gradient)[0] = ((1 - tr) * (b - a) + tr * (e - d)) / grid_.spacing_m;
    (*gradient)[1] = ((1 - tc) * (d - a) + tc * (e - b)) / grid_.spacing_m;
  }
  return true;
}

double TerrainRenderer::March(const Eigen::Vector3d& p_w,
                              double azimuth_rad,
                              std::vector<Visible>* visible) const {
  const double dx = std::sin(azimuth_rad), dy = std::cos(azimuth_rad);
  const double kappa = options_.refraction_k / (2.0 * options_.earth_radius_m);
  const double step = options_.step_spacings * grid_.spacing_m;
  double best = -0.5 * kPi;
  if (visible) visible->clear();
  // The last two samples: where they bracket a local maximum of the elevation, it is refined on
  // a 16 times finer step (the fixed step alone would cut the crests of near ridges).
  double s1 = 0.0, e1 = -kPi, s2 = 0.0, e2 = -kPi;
  const auto elevation = [&](double s, double* e) {
    double z;
    if (!Height(p_w.x() + s * dx, p_w.y() + s * dy, &z, nullptr)) return false;
    *e = std::atan2(z - p_w.z(), s) + kappa * s;
    return true;
  };
  for (double s = options_.min_range_m; s <= options_.max_range_m; s += step) {
    double z;
    Eigen::Vector2d g;
    if (!Height(p_w.x() + s * dx, p_w.y() + s * dy, &z, visible ? &g : nullptr)) {
      e1 = e2 = -kPi;
      continue;
    }
    const double e = std::atan2(z - p_w.z(), s) + kappa * s;
    if (e2 >= e1 && e2 >= e && e2 > best - 1e-3 && s1 > 0.0) {
      for (int i = 1; i < 32; ++i) {
        double ei;
        if (elevation(s1 + (s - s1) * i / 32.0, &ei)) best = std::max(best, ei);
      }
    }
    s1 = s2;
    e1 = e2;
    s2 = s;
    e2 = e;
    if (e <= best) continue;
    best = e;
    if (visible) {
      const double slope = g.norm();
      const Eigen::Vector3d n = Eigen::Vector3d(-g.x(), -g.y(), 1.0).normalized();
      const bool water = slope < 2e-3;
      const double lit = std::max(0.0, n.dot(options_.sun_w));
      const float shade = water ? 0.22f : static_cast<float>(0.42 * (0.3 + 0.7 * lit));
      visible->push_back({static_cast<float>(e), static_cast<float>(s), shade});
    }
  }
  return best;
}

double TerrainRenderer::HorizonElevation(const Eigen::Vector3d& p_w, double azimuth_rad) const {
  return March(p_w, azimuth_rad, nullptr);
}

std::shared_ptr<const std::vector<cv::Point2f>> TerrainRenderer::RaysFor(
    const CameraConfig& camera) const {
  const int w = camera.width_px, h = camera.height_px;
  std::vector<double> key = {double(w), double(h), camera.fx, camera.fy, camera.cx, camera.cy};
  key.insert(key.end(), camera.distortion.begin(), camera.distortion.end());
  {
    const std::lock_guard<std::mutex> lock(rays_mutex_);
    if (rays_ && key == rays_key_) return rays_;
  }
  // The undistorted normalised coordinates of every pixel centre (OpenCV's own inversion).
  std::vector<cv::Point2f> px;
  px.reserve(static_cast<size_t>(w) * h);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) px.emplace_back(static_cast<float>(c), static_cast<float>(r));
  }
  const cv::Matx33d k(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  auto rays = std::make_shared<std::vector<cv::Point2f>>();
  cv::undistortPoints(px, *rays, k, camera.distortion, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 40, 1e-9));
  const std::lock_guard<std::mutex> lock(rays_mutex_);
  rays_ = std::move(rays);
  rays_key_ = std::move(key);
  return rays_;
}

RenderedFrame TerrainRenderer::Render(const CameraConfig& camera,
                                      const Eigen::Quaterniond& q_w_c,
                                      const Eigen::Vector3d& p_w_c,
                                      bool grey,
                                      std::uint64_t noise_seed) const {
  const int w = camera.width_px, h = camera.height_px;
  if (w <= 0 || h <= 0 || !(camera.fx > 0) || !(camera.fy > 0)) {
    throw std::invalid_argument("TerrainRenderer: camera '" + camera.name +
                                "' needs a positive size and focal length");
  }
  const std::shared_ptr<const std::vector<cv::Point2f>> rays_held = RaysFor(camera);
  const std::vector<cv::Point2f>& rays = *rays_held;
  const Eigen::Matrix3d r_w_c = q_w_c.normalized().toRotationMatrix();
  const auto direction = [&](double x, double y, double* az, double* el) {
    const Eigen::Vector3d d = r_w_c * Eigen::Vector3d(x, y, 1.0);
    *az = std::atan2(d.x(), d.y());
    *el = std::atan2(d.z(), std::hypot(d.x(), d.y()));
  };
  // The azimuths the image spans, relative to the optical axis, from its border.
  const Eigen::Vector3d axis = r_w_c.col(2);
  const double az0 = std::atan2(axis.x(), axis.y());
  double lo = 1e9, hi = -1e9;
  const auto border = [&](int c, int r) {
    const cv::Point2f q = rays[static_cast<size_t>(r) * w + c];
    double az, el;
    direction(q.x, q.y, &az, &el);
    const double rel = WrapPi(az - az0);
    lo = std::min(lo, rel);
    hi = std::max(hi, rel);
  };
  for (int c = 0; c < w; c += 8) {
    border(c, 0);
    border(c, h - 1);
  }
  for (int r = 0; r < h; r += 8) {
    border(0, r);
    border(w - 1, r);
  }
  border(w - 1, h - 1);
  const double pad = 0.5 * kPi / 180.0;
  lo -= pad;
  hi += pad;
  const int n_az =
      std::max(8, static_cast<int>(std::ceil(w * options_.azimuth_oversample * (hi - lo) /
                                             std::max(hi - lo - 2 * pad, 1e-3))));
  const double step = (hi - lo) / (n_az - 1);
  std::vector<double> horizon(n_az);
  std::vector<std::vector<Visible>> seen(grey ? n_az : 0);
  for (int i = 0; i < n_az; ++i) {
    horizon[i] = March(p_w_c, az0 + lo + i * step, grey ? &seen[i] : nullptr);
  }
  const auto horizon_at = [&](double az, int* index) {
    const double f = std::clamp((WrapPi(az - az0) - lo) / step, 0.0, n_az - 1.0);
    const int i0 = std::min(static_cast<int>(f), n_az - 2);
    const double t = f - i0;
    if (index) *index = t < 0.5 ? i0 : i0 + 1;
    return (1 - t) * horizon[i0] + t * horizon[i0 + 1];
  };

  RenderedFrame out;
  out.mask = cv::Mat(h, w, CV_8UC1);
  out.skyline_row.assign(w, std::numeric_limits<double>::quiet_NaN());
  for (int r = 0; r < h; ++r) {
    uchar* m = out.mask.ptr<uchar>(r);
    for (int c = 0; c < w; ++c) {
      const cv::Point2f q = rays[static_cast<size_t>(r) * w + c];
      double az, el;
      direction(q.x, q.y, &az, &el);
      m[c] = el > horizon_at(az, nullptr) ? 255 : 0;
    }
  }
  // The true skyline: in each column, the first sky -> terrain step from the top, refined by
  // bisection between the two pixel centres (rays interpolated linearly between them).
  for (int c = 0; c < w; ++c) {
    int r = 0;
    while (r < h && out.mask.at<uchar>(r, c) == 255) ++r;
    if (r == 0 || r == h) continue;
    const cv::Point2f a = rays[static_cast<size_t>(r - 1) * w + c];
    const cv::Point2f b = rays[static_cast<size_t>(r) * w + c];
    double t0 = 0.0, t1 = 1.0;
    for (int it = 0; it < 30; ++it) {
      const double tm = 0.5 * (t0 + t1);
      double az, el;
      direction(a.x + tm * (b.x - a.x), a.y + tm * (b.y - a.y), &az, &el);
      (el > horizon_at(az, nullptr) ? t0 : t1) = tm;
    }
    out.skyline_row[c] = r - 1 + 0.5 * (t0 + t1);
  }
  if (!grey) return out;

  // The grey image: sky brightening towards the horizon, terrain and water shaded and hazed.
  out.grey = cv::Mat(h, w, CV_8UC1);
  std::mt19937_64 rng(noise_seed);
  std::normal_distribution<double> noise(0.0, options_.noise_grey);
  const auto sky_level = [](double el) {
    return 150.0 + 85.0 * std::exp(-std::max(el, 0.0) / 0.3);
  };
  for (int r = 0; r < h; ++r) {
    uchar* g = out.grey.ptr<uchar>(r);
    const uchar* m = out.mask.ptr<uchar>(r);
    for (int c = 0; c < w; ++c) {
      const cv::Point2f q = rays[static_cast<size_t>(r) * w + c];
      double az, el;
      direction(q.x, q.y, &az, &el);
      double v;
      if (m[c] == 255) {
        v = sky_level(el);
      } else {
        int i = 0;
        horizon_at(az, &i);
        const std::vector<Visible>& list = seen[i];
        const auto it = std::lower_bound(
            list.begin(), list.end(), el,
            [](const Visible& x, double e) { return static_cast<double>(x.elevation) < e; });
        double distance, shade;
        if (it == list.end() || list.empty()) {
          distance = list.empty() ? 1.0 : list.back().distance;
          shade = list.empty() ? 0.22 : list.back().shade;
        } else {
          distance = it->distance;
          shade = it->shade;
        }
        const double t = std::exp(-distance / options_.visibility_m);
        v = 255.0 * shade * t + sky_level(0.0) * (1.0 - t);
      }
      g[c] = static_cast<uchar>(std::clamp(std::lround(v + noise(rng)), 0L, 255L));
    }
  }
  return out;
}

}  // namespace skerry::sim
