#include "skerry/skyline/crest_correlation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace skerry::skyline {
bool HorizonOnWater(const HorizonPredictor& horizon, const Eigen::Vector3d& point_w) {
  const geo::EnuHeightGrid& g = horizon.grid();
  const int col = static_cast<int>(std::lround((point_w.x() - g.origin_w.x()) / g.spacing_m));
  const int row = static_cast<int>(std::lround((point_w.y() - g.origin_w.y()) / g.spacing_m));
  return g.LevelAround(col, row, horizon.options().earth_radius_m);
}

CrestMotion MeasureCrestMotion(const HorizonPredictor& horizon,
                               const std::vector<Eigen::Vector3d>& now_w,
                               const Eigen::Vector3d& p_prev_w_c,
                               double length_m) {
  if (!(length_m > 0)) throw std::invalid_argument("MeasureCrestMotion: length_m must be > 0");
  CrestMotion out;
  std::vector<double> shifts;
  shifts.reserve(now_w.size());
  double sum = 0.0;
  for (const Eigen::Vector3d& now : now_w) {
    if (!now.allFinite()) continue;
    ++out.samples;
    if (HorizonOnWater(horizon, now)) {
      ++out.water;
      continue;
    }
    const Eigen::Vector2d towards = now.head<2>() - p_prev_w_c.head<2>();
    if (!(towards.norm() > 0)) continue;
    const HorizonSample before = horizon.Trace(p_prev_w_c, std::atan2(towards.x(), towards.y()));
    if (!before.valid || before.truncated) continue;
    ++out.compared;
    const double shift = (now.head<2>() - before.point_w.head<2>()).norm();
    shifts.push_back(shift);
    sum += std::exp(-shift / length_m);
  }
  if (out.samples > 0) out.rho = std::clamp(sum / out.samples, 0.0, 1.0);
  if (!shifts.empty()) {
    const auto mid = shifts.begin() + static_cast<long>(shifts.size() / 2);
    std::nth_element(shifts.begin(), mid, shifts.end());
    out.median_shift_m = *mid;
  }
  return out;
}

CrestMotion MeasureCrestMotion(const HorizonPredictor& horizon,
                               const std::vector<Eigen::Vector3d>& rays_c,
                               const Eigen::Matrix3d& r_w_c,
                               const Eigen::Vector3d& p_w_c,
                               const Eigen::Vector3d& p_prev_w_c,
                               double length_m) {
  if (!(length_m > 0)) throw std::invalid_argument("MeasureCrestMotion: length_m must be > 0");
  std::vector<Eigen::Vector3d> now_w;
  now_w.reserve(rays_c.size());
  for (const Eigen::Vector3d& ray : rays_c) {
    const Eigen::Vector3d r_w = r_w_c * ray;
    // Azimuth clockwise from north, as the residual takes it (skyline_residual.h).
    const HorizonSample now = horizon.Trace(p_w_c, std::atan2(r_w.x(), r_w.y()));
    now_w.push_back(now.valid && !now.truncated
                        ? now.point_w
                        : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  }
  return MeasureCrestMotion(horizon, now_w, p_prev_w_c, length_m);
}

}  // namespace skerry::skyline
