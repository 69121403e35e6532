#pragma once
/// \file
/// A camera's view of a DEM terrain for the simulator: a segmentation mask (sky / not sky) and
/// a shaded grey image with haze, from the camera's true pose. Deliberately independent of the
/// estimator's horizon predictor (frontends/skyline): its own ray march (fixed steps, no pyramid),
/// its own bilinear lookup and OpenCV's undistortion, so that the skyline the estimator is given
/// is not its own model's output.
///
/// Model. In the local ENU frame `w`, with the terrain's ENU up coordinate on a grid (Earth
/// curvature included), the horizon along azimuth a is the highest apparent elevation
/// atan2(z_t - z_c, s) + k s / (2 R) over distance s (refraction coefficient k). A pixel is sky
/// when its ray's elevation exceeds the horizon at its azimuth. Below the horizon a pixel sees
/// the first terrain point whose elevation reaches the ray's (the march records them as it goes
/// outward); it is shaded by its slope against the sun, water (flat) darker, and hazed towards
/// the horizon's sky with distance (Koschmieder: t = exp(-s / visibility)). Not modelled: clouds,
/// sun glare, boats, vegetation texture, lens vignetting, motion blur, rolling shutter.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <vector>

#include "skerry/core/sensor_config.h"
#include "skerry/geo/enu_height_grid.h"

namespace skerry::sim {

struct TerrainRenderOptions {
  double refraction_k = 0.13;
  double earth_radius_m = 6371000.0;
  double min_range_m = 30.0;
  double max_range_m = 60000.0;
  /// Profile azimuths per pixel across the image.
  double azimuth_oversample = 1.5;
  /// March step in grid spacings.
  double step_spacings = 0.5;
  /// Visibility for the haze, m.
  double visibility_m = 40000.0;
  /// Direction to the sun (ENU, normalised inside).
  Eigen::Vector3d sun_w = Eigen::Vector3d(-0.4, -0.6, 0.7);
  /// Pixel noise of the grey image (grey levels, 1 sigma).
  double noise_grey = 2.0;
};

struct RenderedFrame {
  cv::Mat mask;  ///< CV_8UC1: 255 sky, 0 terrain or water
  cv::Mat grey;  ///< CV_8UC1 shaded image (empty unless asked for)
  /// Per column: the true skyline row (continuous, pixel centres at integers); NaN where the
  /// column has no skyline in the image.
  std::vector<double> skyline_row;
};

class TerrainRenderer {
 public:
  /// std::invalid_argument for a grid smaller than 2x2 or a spacing <= 0.
  TerrainRenderer(geo::EnuHeightGrid grid, const TerrainRenderOptions& options = {});

  /// Renders a camera (OpenCV model) at T_w_c (optical frame: x right, y down, z forward).
  /// `noise_seed` seeds the grey image's pixel noise. Safe to call from several threads at once
  /// (the camera's undistorted rays are cached under a lock).
  RenderedFrame Render(const CameraConfig& camera,
                       const Eigen::Quaterniond& q_w_c,
                       const Eigen::Vector3d& p_w_c,
                       bool grey,
                       std::uint64_t noise_seed) const;

  /// The horizon's apparent elevation (rad) along an azimuth from p_w, by the fixed-step march.
  double HorizonElevation(const Eigen::Vector3d& p_w, double azimuth_rad) const;

  const geo::EnuHeightGrid& grid() const { return grid_; }

 private:
  struct Visible {
    float elevation;  ///< apparent elevation at which this terrain point becomes visible
    float distance;
    float shade;  ///< 0..1 lit albedo
  };
  /// Marches one azimuth: the horizon's elevation, and (if `visible`) the terrain points seen.
  double March(const Eigen::Vector3d& p_w, double azimuth_rad, std::vector<Visible>* visible) const;
  bool Height(double x, double y, double* z, Eigen::Vector2d* gradient) const;

  geo::EnuHeightGrid grid_;
  TerrainRenderOptions options_;
  /// The undistorted (x/z, y/z) of every pixel, row-major, for the camera of `rays_key_`.
  std::shared_ptr<const std::vector<cv::Point2f>> RaysFor(const CameraConfig& camera) const;
  mutable std::mutex rays_mutex_;
  mutable std::shared_ptr<const std::vector<cv::Point2f>> rays_;
  mutable std::vector<double> rays_key_;
};

}  // namespace skerry::sim
