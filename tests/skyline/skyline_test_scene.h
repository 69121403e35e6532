#pragma once
// Synthetic terrain for the skyline tests: a sea with a ring of smooth mountains around the
// origin (so every azimuth has a skyline), and skyline samples made from a known camera pose by
// the horizon predictor itself (the factor's own model: these tests check the factor and its
// solve; the independent renderer of the simulator checks the model).

#include <cmath>
#include <functional>
#include <memory>
#include <vector>

#include "skerry/skyline/camera_model.h"
#include "skerry/skyline/horizon_predictor.h"
#include "skerry/skyline/skyline_residual.h"

namespace skerry::skyline::testing {

/// An n x n grid centred on the origin with z = height(x, y) at its nodes.
inline geo::EnuHeightGrid Grid(int n,
                               double spacing,
                               const std::function<double(double, double)>& height) {
  geo::EnuHeightGrid g;
  g.origin_w = Eigen::Vector2d(-0.5 * (n - 1) * spacing, -0.5 * (n - 1) * spacing);
  g.spacing_m = spacing;
  g.cols = g.rows = n;
  g.up_m.resize(static_cast<size_t>(n) * n);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const Eigen::Vector2d p = g.NodePosition(c, r);
      g.up_m[static_cast<size_t>(r) * n + c] = height(p.x(), p.y());
    }
  }
  return g;
}

inline geo::EnuHeightGrid MountainRing(int n = 801, double spacing = 25.0) {
  return Grid(n, spacing, [](double x, double y) {
    const double d = std::hypot(x, y), a = std::atan2(x, y);
    // Peaks of varying height on a ring 5-8 km out: an irregular skyline all round.
    const double ring = std::exp(-std::pow((d - 6500.0) / 1200.0, 2));
    const double peaks = 300.0 + 180.0 * std::sin(3 * a) + 120.0 * std::sin(7 * a + 1.0) +
                         60.0 * std::sin(13 * a + 2.0);
    return ring * peaks - d * d / (2 * 6371000.0);
  });
}

/// The mountain ring with its land (0.5 m or more above the curved sea) raised by `by` metres:
/// terrain whose crests stand above the map's (a raster's crest deficit).
inline geo::EnuHeightGrid RaisedMountainRing(double by, int n = 801, double spacing = 25.0) {
  geo::EnuHeightGrid g = MountainRing(n, spacing);
  for (int r = 0; r < g.rows; ++r) {
    for (int c = 0; c < g.cols; ++c) {
      const Eigen::Vector2d p = g.NodePosition(c, r);
      double& z = g.up_m[static_cast<size_t>(r) * g.cols + c];
      if (z + p.squaredNorm() / (2 * 6371000.0) > 0.5) z += by;
    }
  }
  return g;
}

/// The skyline a camera at (R_w_c, p_w_c) sees of the predictor's terrain, every `stride`
/// columns: for each column, the row where the ray's elevation equals the horizon (bisection).
inline std::vector<SkylineSample> SyntheticSkyline(const HorizonPredictor& horizon,
                                                   const CameraModel& camera,
                                                   const Eigen::Matrix3d& r_w_c,
                                                   const Eigen::Vector3d& p_w_c,
                                                   int stride) {
  std::vector<SkylineSample> out;
  for (int u = stride / 2; u < camera.width(); u += stride) {
    const auto diff = [&](double v) {
      const Eigen::Vector3d r = r_w_c * *camera.Ray({double(u), v});
      const HorizonSample h = horizon.Trace(p_w_c, std::atan2(r.x(), r.y()));
      return std::atan2(r.z(), std::hypot(r.x(), r.y())) - h.elevation_rad;
    };
    double lo = 0.0, hi = camera.height() - 1.0;  // sky above (diff > 0) at lo
    if (!(diff(lo) > 0 && diff(hi) < 0)) continue;
    for (int it = 0; it < 40; ++it) {
      const double mid = 0.5 * (lo + hi);
      (diff(mid) > 0 ? lo : hi) = mid;
    }
    out.push_back({Eigen::Vector2d(u, 0.5 * (lo + hi)), 1.0});
  }
  return out;
}

}  // namespace skerry::skyline::testing
