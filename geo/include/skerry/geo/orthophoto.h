#pragma once
/// \file
/// A georeferenced aerial image (GeoTIFF, or JPEG/PNG with a world file) in any CRS, with
/// exact pixel <-> local ENU conversions through the CRS transform and the LocalFrame.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "skerry/core/geodesy.h"

namespace skerry::geo {

struct OrthophotoOptions {
  /// CRS override: "EPSG:2992", WKT text, a PROJ string, or the path of a .prj / .wkt file.
  /// Empty: the image's own CRS (GeoTIFF), else a sidecar next to it: STEM.prj, STEM.wkt or
  /// STEM-srs.wkt (in that order). No CRS at all is an InputError.
  std::string crs;
  /// Where the caller takes `crs` from, named in the error when the image has no CRS, so that
  /// the user reads the flag or key they can set ("--image-crs", "maps.orthophoto.crs in
  /// DIR/dataset.yaml").
  std::string crs_given_as = "OrthophotoOptions::crs";
  /// The most pixels held in memory at once: the whole image's, or with `on_disk` each window's
  /// (Orthophoto::Pixels). More is an InputError (field "size") before anything is allocated (a
  /// GeoTIFF header of a few hundred bytes can declare 10^10). 2^28 pixels (768 MiB in BGR) hold
  /// a 2.6 km square at 0.16 m/px.
  std::int64_t max_pixels = std::int64_t{1} << 28;
  /// Leave the pixels in the file and read the windows asked for (Orthophoto::Pixels): an image
  /// of a whole county costs the memory of the part around the track. The georeferencing, the
  /// CRS and a deeper image's stretch (over the whole image, read strip by strip) are as in
  /// memory, and so is every window's content.
  bool on_disk = false;
  /// An image of 16-bit, 32-bit or floating-point cells is stretched linearly onto 0..255 between
  /// the `clip_fraction` and 1 - `clip_fraction` quantiles of its valid cells (all used bands
  /// together, no-data and NaN left out), so that a few hot pixels do not squeeze the scene into
  /// a few grey levels. In [0, 0.5); 0 stretches between the minimum and the maximum.
  double clip_fraction = 0.005;
};

/// A window of an orthophoto's pixels: `rect` (inside the image; empty when the window asked for
/// misses it), `image` and `valid` as Orthophoto::image() and valid_mask() hold them there
/// (`valid` empty when every pixel of the window holds data), or reduced `factor` times along
/// each axis (Orthophoto::Pixels(window, factor)): pixel (i, j) of `image` then stands for the
/// image's pixels from (rect.x + i * factor, rect.y + j * factor), `factor` of them each way,
/// centred on (rect.x + i * factor + (factor - 1) / 2, rect.y + j * factor + (factor - 1) / 2)
/// (blocks cut short by the window's right or bottom edge on the pixels they hold).
struct OrthophotoPixels {
  cv::Rect rect;
  cv::Mat image;
  cv::Mat valid;
  int factor = 1;
};

/// An orthophoto, its pixels held in memory or read by window from the file
/// (OrthophotoOptions::on_disk).
///
/// Pixel convention (OpenCV's): (u, v) = (column, row) with the *centre* of pixel (0, 0) at
/// (0, 0); the image covers [-0.5, width - 0.5] x [-0.5, height - 0.5]. (GDAL's geotransform
/// is corner-based: map (x, y) = GT(u + 0.5, v + 0.5).)
///
/// Georeferencing comes from GDAL: the GeoTIFF tags or the world file GDAL picks up itself
/// (.wld, .jgw, .pgw, .tfw...); only when GDAL reports none is a world file read, still through
/// GDAL's GDALReadWorldFile. An orthophoto's pixel gives a horizontal position only: heights are
/// the caller's.
///
/// Thread safety: conversions are const and serialised by a mutex around PROJ.
class Orthophoto {
 public:
  /// Reads the image: 1 band -> gray, an 8-bit palette or 3-4 bands -> BGR. 8-bit cells are taken
  /// as they are; 16-bit, 32-bit and floating-point ones are stretched onto 8 bits
  /// (OrthophotoOptions::clip_fraction), their no-data, NaN and infinite cells becoming 0.
  /// Pixels that hold no data (valid_mask()) are 0 in every channel. Throws InputError naming
  /// `path` when it cannot be read, holds complex numbers or no valid cell, has no
  /// georeferencing or no CRS.
  Orthophoto(const std::string& path,
             const LocalFrame& frame,
             const OrthophotoOptions& options = {});
  ~Orthophoto();
  Orthophoto(Orthophoto&&) noexcept;
  Orthophoto& operator=(Orthophoto&&) noexcept;

  /// CV_8UC1 (gray) or CV_8UC3 (BGR); empty when the pixels stay on disk (Pixels()).
  const cv::Mat& image() const;
  /// The cell values of the file that became 0 and 255 in image(): (0, 255) for an 8-bit image,
  /// the stretch's quantiles for a deeper one.
  const Eigen::Vector2d& value_range() const;
  /// Where the image holds data: CV_8UC1, 255 or 0, empty when every pixel does (or when the
  /// pixels stay on disk: Pixels() has each window's). A pixel holds
  /// none when, in every used band, GDAL's mask says so (its no-data value, a transparent alpha
  /// band, a .msk file: GDAL RFC 15) or its deeper cell is NaN or infinite. A reprojected or
  /// clipped mosaic's corners, a masked sea: the step from them to the photo is no edge of the
  /// world (AerialMap leaves them out).
  const cv::Mat& valid_mask() const;
  /// The share of pixels that hold data (1 when valid_mask() is empty; NaN when the pixels stay
  /// on disk: not counted).
  double valid_share() const;
  int width() const;
  int height() const;
  /// The pixels stay in the file (OrthophotoOptions::on_disk).
  bool on_disk() const;
  /// The pixels of `window` (clipped to the image): views of image() and valid_mask(), or read
  /// from the file when the pixels stay on disk (serialised; InputError "size" for a window of
  /// more than OrthophotoOptions::max_pixels, or naming the file when it cannot be read).
  OrthophotoPixels Pixels(const cv::Rect& window) const;
  /// The pixels of `window` (clipped to the image) reduced `factor` (>= 1) times along each axis:
  /// each pixel of the result is the mean, rounded, of its block of factor x factor pixels (fewer
  /// at the window's right and bottom edges) over those that hold data, and holds data when at
  /// least half of them do (0 in every channel when it does not). A photo far finer than the use
  /// made of it (a drone's 3 cm mosaic for a map of 0.25 m cells) is read from disk in strips of
  /// whole blocks (at most 4 million pixels and max_pixels, or one row of blocks), and only the
  /// reduced window is held: OrthophotoOptions::max_pixels bounds it, not the window. The same to
  /// the bit on disk and in memory; factor 1 is Pixels(window).
  OrthophotoPixels Pixels(const cv::Rect& window, int factor) const;

  /// ENU point of pixel (u, v) at ellipsoidal height height_m. Throws std::runtime_error if the
  /// CRS transform fails (a pixel far outside the CRS's domain).
  Eigen::Vector3d PixelToEnu(double u, double v, double height_m = 0.0) const;
  /// Pixel (u, v) of the ENU point (its height is irrelevant: the map is orthographic). NaN if
  /// the point cannot be placed in the image's CRS.
  Eigen::Vector2d EnuToPixel(const Eigen::Vector3d& p_w) const;
  /// The point lies over the image (its pixel inside the image's outer edge), whether that pixel
  /// holds data or not (valid_mask()).
  bool Covers(const Eigen::Vector3d& p_w) const;
  /// The point lies over a pixel that holds data (Covers, and valid_mask() set at the nearest
  /// pixel).
  bool HoldsData(const Eigen::Vector3d& p_w) const;

  /// The image's outer edge in ENU (x, y) at the frame origin's height: 16 points per side,
  /// counter-clockwise, not closed (the CRS may curve straight map edges slightly).
  const std::vector<Eigen::Vector2d>& footprint_enu() const;
  const Eigen::AlignedBox2d& footprint_box_enu() const;
  /// Distance (m) on the ellipsoid between neighbouring pixel centres along a row (x) and a
  /// column (y), at the image centre; ground_sample_distance_m() is their mean.
  Eigen::Vector2d gsd_m() const;
  double ground_sample_distance_m() const;

  const std::string& path() const;
  /// WKT2 of the CRS used, and where it came from ("file", "sidecar PATH" or "override").
  const std::string& crs_wkt() const;
  const std::string& crs_source() const;
  const LocalFrame& frame() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace skerry::geo
