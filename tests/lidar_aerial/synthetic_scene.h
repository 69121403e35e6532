#pragma once
// A small synthetic world for the LiDAR-to-aerial tests: boxes (quays, piers, buildings) and
// ground paint on a flat ground, rendered as a georeferenced aerial image (PNG + world file,
// UTM 32N) and sampled as a levelled LiDAR scan from a planar pose. Both come from one scene, so
// the registration between them is exact: what the tests recover is the pose they were made at.

#include <Eigen/Core>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "geo/geo_test_util.h"
#include "skerry/core/geodesy.h"
#include "skerry/geo/orthophoto.h"
#include "skerry/lidar_aerial/planar_pose.h"

namespace skerry::lidar_aerial::testing {

// A rectangle in grid metres (x east, y north from the image's south-west corner), rotated by
// `yaw` about its centre.
struct Box {
  Eigen::Vector2d centre;
  Eigen::Vector2d size;
  double yaw = 0.0;
  double height = 2.0;  // 0: ground paint
  int grey = 200;       // in the image
  float intensity = 60.0f;
};

struct Scene {
  double width_m = 200.0, height_m = 200.0;
  double gsd_m = 0.1;
  int ground_grey = 90;
  float ground_intensity = 20.0f;
  std::vector<Box> boxes;

  // Corners of a box, counter-clockwise.
  static std::vector<Eigen::Vector2d> Corners(const Box& b) {
    const PlanarPose pose{b.centre, b.yaw};
    const Eigen::Vector2d h = 0.5 * b.size;
    return {pose.Apply({-h.x(), -h.y()}), pose.Apply({h.x(), -h.y()}), pose.Apply({h.x(), h.y()}),
            pose.Apply({-h.x(), h.y()})};
  }
  static bool Inside(const Box& b, const Eigen::Vector2d& p) {
    const Eigen::Vector2d q = PlanarPose{b.centre, b.yaw}.R().transpose() * (p - b.centre);
    return std::abs(q.x()) <= 0.5 * b.size.x() && std::abs(q.y()) <= 0.5 * b.size.y();
  }
};

// Writes scene.png with its world file and returns the path; the CRS goes in as an override
// ("EPSG:32632"). Grid (x, y) metres <-> pixel (x / gsd - 0.5, (H - y) / gsd - 0.5).
inline std::string WriteAerialImage(const Scene& s, const std::string& dir) {
  const int w = static_cast<int>(std::lround(s.width_m / s.gsd_m));
  const int h = static_cast<int>(std::lround(s.height_m / s.gsd_m));
  cv::Mat img(h, w, CV_8UC1, cv::Scalar(s.ground_grey));
  for (const Box& b : s.boxes) {
    std::vector<cv::Point> poly;
    for (const Eigen::Vector2d& c : Scene::Corners(b)) {
      // Sub-pixel corners (shift 4: 1/16 px); OpenCV's integer coordinates are pixel centres.
      poly.emplace_back(
          static_cast<int>(std::lround(16.0 * (c.x() / s.gsd_m - 0.5))),
          static_cast<int>(std::lround(16.0 * ((s.height_m - c.y()) / s.gsd_m - 0.5))));
    }
    cv::fillPoly(img, std::vector<std::vector<cv::Point>>{poly}, cv::Scalar(b.grey), cv::LINE_AA,
                 4);
  }
  const std::string path = dir + "/scene.png";
  cv::imwrite(path, img);
  // World file: pixel size, rotation terms, then the centre of the top-left pixel.
  const double e0 = 500000.0, n0 = 5000000.0;  // UTM 32N, the south-west corner
  geo::testing::WriteText(dir + "/scene.pgw",
                          std::to_string(s.gsd_m) + "\n0\n0\n" + std::to_string(-s.gsd_m) + "\n" +
                              std::to_string(e0 + 0.5 * s.gsd_m) + "\n" +
                              std::to_string(n0 + s.height_m - 0.5 * s.gsd_m) + "\n");
  return path;
}

// The orthophoto of the scene with its ENU frame at the image centre.
inline geo::Orthophoto LoadScene(const std::string& path) {
  geo::OrthophotoOptions o;
  o.crs = "EPSG:32632";
  const geo::Orthophoto rough(path, LocalFrame({45.1, 9.0, 0.0}), o);
  const Eigen::Vector3d llh = rough.frame().ToGeodetic(
      rough.PixelToEnu(0.5 * (rough.width() - 1), 0.5 * (rough.height() - 1), 0.0));
  return geo::Orthophoto(path, LocalFrame({llh.x(), llh.y(), 0.0}), o);
}

// ENU of a grid point of the scene (through the image's own georeferencing).
inline Eigen::Vector2d GridToEnu(const Scene& s,
                                 const geo::Orthophoto& ortho,
                                 const Eigen::Vector2d& g) {
  return ortho.PixelToEnu(g.x() / s.gsd_m - 0.5, (s.height_m - g.y()) / s.gsd_m - 0.5).head<2>();
}

struct Scan {
  std::vector<Eigen::Vector3d> points_l;  // levelled sensor frame
  std::vector<float> intensity;
};

// A LiDAR scan of the scene from a sensor at ENU planar pose `sensor_w` (height 0 above the
// ground plane): the ground every `step` metres within `range`, every box's top and its faces
// (every `step` along the perimeter, every 0.2 m up). No occlusion: what matters here is which
// columns are structure and where they are.
inline Scan SampleScan(const Scene& s,
                       const geo::Orthophoto& ortho,
                       const PlanarPose& sensor_w,
                       double range,
                       double step = 0.25) {
  Scan scan;
  const Eigen::Matrix2d Rt = sensor_w.R().transpose();
  // Grid -> ENU is affine to well below a millimetre over the scene (UTM on its central
  // meridian); exact lookups at three points fix it.
  const Eigen::Vector2d o = GridToEnu(s, ortho, {0.0, 0.0});
  Eigen::Matrix2d A;
  A.col(0) = (GridToEnu(s, ortho, {100.0, 0.0}) - o) / 100.0;
  A.col(1) = (GridToEnu(s, ortho, {0.0, 100.0}) - o) / 100.0;
  const Eigen::Vector2d sensor_g = A.inverse() * (sensor_w.t - o);
  const auto add = [&](const Eigen::Vector2d& grid, double z, float intensity) {
    const Eigen::Vector2d w = o + A * grid;
    const Eigen::Vector2d l = Rt * (w - sensor_w.t);
    if (l.norm() > range) return;
    scan.points_l.emplace_back(l.x(), l.y(), z);
    scan.intensity.push_back(intensity);
  };
  const double y0 = std::max(0.0, std::floor((sensor_g.y() - range) / step) * step);
  const double x0 = std::max(0.0, std::floor((sensor_g.x() - range) / step) * step);
  for (double y = y0 + 0.5 * step; y < std::min(s.height_m, sensor_g.y() + range); y += step) {
    for (double x = x0 + 0.5 * step; x < std::min(s.width_m, sensor_g.x() + range); x += step) {
      const Eigen::Vector2d g(x, y);
      double z = 0.0;
      float in = s.ground_intensity;
      for (const Box& b : s.boxes) {
        if (!Scene::Inside(b, g)) continue;
        z = std::max(z, b.height);
        in = b.intensity;
      }
      add(g, z, in);
    }
  }
  for (const Box& b : s.boxes) {
    if (b.height <= 0.0) continue;
    const std::vector<Eigen::Vector2d> c = Scene::Corners(b);
    for (size_t k = 0; k < c.size(); ++k) {
      const Eigen::Vector2d a = c[k], d = c[(k + 1) % c.size()] - c[k];
      const int n = static_cast<int>(d.norm() / (0.4 * step));
      for (int i = 0; i <= n; ++i) {
        for (double z = 0.1; z < b.height; z += 0.2) add(a + d * (i / double(n)), z, b.intensity);
      }
    }
  }
  return scan;
}

// A harbour-like scene: an L-shaped quay, a pier, two buildings, a mooring dolphin, paint.
inline Scene Harbour() {
  Scene s;
  s.boxes = {
      {{60, 100}, {40, 120}, 0.0, 2.0, 170, 50},   // quay, west
      {{120, 40}, {100, 30}, 0.0, 2.0, 170, 50},   // quay, south
      {{125, 110}, {8, 60}, 0.15, 1.8, 200, 60},   // pier
      {{50, 70}, {16, 24}, 0.3, 2.5, 230, 80},     // building on the quay
      {{150, 35}, {12, 10}, -0.2, 2.5, 60, 80},    // dark building
      {{100, 80}, {3, 3}, 0.0, 2.0, 220, 70},      // dolphin
      {{75, 130}, {1.0, 30}, 0.0, 0.0, 250, 200},  // paint on the west quay
      {{110, 45}, {40, 1.0}, 0.0, 0.0, 250, 200},  // paint on the south quay
  };
  // The paint lies on the quays: at the quay's height.
  s.boxes[6].height = 0.0;
  s.boxes[7].height = 0.0;
  return s;
}

}  // namespace skerry::lidar_aerial::testing
