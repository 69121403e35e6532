#pragma once
/// \file
/// A georeferenced aerial image turned into what LiDAR alignment needs: the image resampled onto
/// a north-up grid of the local ENU frame `w`, its edges, and the distance from every cell to the
/// nearest edge (metres), for any orthophoto the geodata layer reads (geo::Orthophoto).
///
/// Why edges and distances. What a LiDAR and a camera looking down both see are boundaries:
/// quay walls, piers, building outlines and kerbs are steps in height for the one and steps in
/// brightness for the other; surfaces are not comparable (intensity is not reflectance is not
/// colour). The distance field turns "this point lies on an edge" into a smooth residual whose
/// gradient points to the nearest edge (chamfer matching: Barrow et al. 1977, "Parametric
/// correspondence and chamfer matching"; Borgefors 1988); it is the fine alignment's map. The
/// edge image, blurred, is the coarse search's map (coarse_search.h).
///
/// Resampling. Pixel (c, r) of the grid is at ENU (x0 + c s, y1 - r s) (row 0 north). The
/// orthophoto's CRS is generally not aligned with ENU (a Lambert grid is rotated by the meridian
/// convergence, 1.8 degrees at Autzen), so each cell is looked up through the CRS transform:
/// exactly at the nodes of a lattice every 16 cells, bilinearly between them (the transform is
/// smooth over 16 cells; the interpolation error is reported in `lattice_error_px`). The image is
/// blurred by half a cell before it is sampled (anti-aliasing); a photo more than 4 times finer
/// than the cells (a drone's centimetre mosaic) is first read as means of blocks of pixels
/// (geo::Orthophoto::Pixels(window, factor)) that leave 2 to 4 of them across a cell, so that
/// only those are held.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <optional>

#include "skerry/geo/orthophoto.h"

namespace skerry::lidar_aerial {

struct AerialMapOptions {
  double resolution_m = 0.25;  ///< grid cell size
  /// Gaussian blur before edge detection, in metres (removes texture finer than structure).
  double blur_m = 0.5;
  /// Canny's thresholds as quantiles of the blurred image's gradient magnitude: the share of
  /// cells that is *not* a strong / weak edge candidate. Quantiles adapt to the image's contrast.
  double canny_high_quantile = 0.90;
  double canny_low_quantile = 0.75;
  /// Distances beyond this are clipped: a point far from every edge is an outlier, not a pull.
  double max_distance_m = 5.0;
  /// Where the photograph was taken from (ENU, m), when known: the alignment then models the
  /// outlines its perspective displaces (relief_displacement.h). Unknown (a true orthophoto, or
  /// a mosaic of many frames): outlines are taken where the image has them.
  std::optional<Eigen::Vector3d> viewpoint_w;
};

class AerialMap {
 public:
  /// The part of `ortho` inside `box_w` (ENU x/y), at options.resolution_m. Cells outside the
  /// image or on its pixels without data (geo::Orthophoto::valid_mask) are marked invalid: no
  /// edge is found within 3 cells of them and their distance is max_distance_m. Throws InputError
  /// naming the image when the box does not overlap it.
  AerialMap(const geo::Orthophoto& ortho,
            const Eigen::AlignedBox2d& box_w,
            const AerialMapOptions& options = {});

  /// Grid pixel (column, row; cell centres at integers) of an ENU point, and back.
  Eigen::Vector2d ToGrid(const Eigen::Vector2d& xy_w) const {
    return {(xy_w.x() - x0_) / resolution_m_, (y1_ - xy_w.y()) / resolution_m_};
  }
  Eigen::Vector2d ToEnu(const Eigen::Vector2d& cr) const {
    return {x0_ + cr.x() * resolution_m_, y1_ - cr.y() * resolution_m_};
  }
  /// The ENU point lies on a valid cell (inside the image, on a pixel with data).
  bool Covers(const Eigen::Vector2d& xy_w) const;

  double resolution_m() const { return resolution_m_; }
  int cols() const { return grey_.cols; }
  int rows() const { return grey_.rows; }
  const std::string& source() const { return source_; }
  const AerialMapOptions& options() const { return options_; }

  const cv::Mat& grey() const { return grey_; }          ///< CV_8UC1, the resampled image
  const cv::Mat& valid() const { return valid_; }        ///< CV_8UC1, 255 where the image is
  const cv::Mat& edges() const { return edges_; }        ///< CV_8UC1, 255 on Canny edges
  const cv::Mat& distance() const { return distance_; }  ///< CV_32FC1, metres to an edge
  /// Largest distance (px) between the lattice-interpolated and the exact image pixel of a cell,
  /// over the lattice cells' centres (where the interpolation is worst).
  double lattice_error_px() const { return lattice_error_px_; }

 private:
  AerialMapOptions options_;
  std::string source_;
  double resolution_m_ = 0.0;
  double x0_ = 0.0;  ///< ENU x of column 0's centre
  double y1_ = 0.0;  ///< ENU y of row 0's centre
  cv::Mat grey_, valid_, edges_, distance_;
  double lattice_error_px_ = 0.0;
};

}  // namespace skerry::lidar_aerial
