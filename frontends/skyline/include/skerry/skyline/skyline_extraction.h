#pragma once
/// \file
/// The skyline of an image: per column, the row where the sky ends (sub-pixel), with a
/// confidence, and gaps where no skyline is seen (clouds down to the terrain, glare, a boat in
/// front, no sky at all).
///
/// Rows are continuous image coordinates with pixel centres at integers: a boundary between a
/// sky pixel in row r and a terrain pixel in row r + 1 lies at r + 0.5.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "skerry/skyline/camera_model.h"
#include "skerry/skyline/skyline_residual.h"

namespace skerry::skyline {

struct Skyline {
  int width = 0, height = 0;
  std::vector<double> row;        ///< per column; NaN = gap
  std::vector<float> confidence;  ///< per column, 0..1 (0 in gaps)
  int valid_columns() const;
};

struct MaskExtractionOptions {
  /// Opening then closing with a square of this size (px) removes speckle and small holes, as
  /// prior work's morphology did (<= 1: none).
  int morphology_px = 3;
};

/// From a segmentation mask (CV_8U, sky 255, anything else 0; grey levels are partial sky):
/// the sky connected to the image's top edge, cleaned by morphology; per column the first sky ->
/// not-sky transition from the top, sub-pixel where the mask crosses 127.5 between pixel
/// centres (an anti-aliased mask); confidence 1. A column whose sky reaches the bottom or that
/// has none is a gap; a mask without sky is all gaps. std::invalid_argument for an empty or
/// non-CV_8UC1 image.
Skyline ExtractSkylineFromMask(const cv::Mat& mask, const MaskExtractionOptions& options = {});

struct ImageExtractionOptions {
  /// The boundary is found at this width first (dynamic programming), then refined at full
  /// resolution.
  int work_width_px = 480;
  /// Largest row jump between neighbouring columns at work resolution, and its cost per row.
  int max_jump_px = 6;
  double jump_cost = 0.04;
  /// Weight of the sky-likeness contrast (above minus below) against the edge strength.
  double region_weight = 1.0;
  /// Columns whose confidence falls below this are gaps.
  double min_confidence = 0.25;
};

/// From an ordinary photo (CV_8UC3 BGR or CV_8UC1 grey): a sky likelihood per pixel (bright,
/// little texture, blue or unsaturated), and a path across the columns at work resolution
/// maximising edge strength (bright above, darker below) plus the sky likelihood above it and
/// its absence below, with a cost on row jumps (dynamic programming, in the manner of Lie et
/// al. 2005, "A robust dynamic programming algorithm to extract skyline in images for
/// navigation", Pattern Recognition Letters 26); refined per full-resolution column to the
/// strongest vertical gradient near the path, sub-pixel by a parabola through it. Confidence
/// from the edge's contrast and the sky likelihood above; low-confidence columns (a cloud down
/// on the ridge, glare) are gaps. std::invalid_argument for an empty image or another type.
Skyline ExtractSkylineFromImage(const cv::Mat& image, const ImageExtractionOptions& options = {});

/// Whether a single-channel image holds only 0 and 255 (and grey levels at boundaries only): a
/// segmentation mask rather than a photo. Used by skyline.source auto.
bool LooksLikeMask(const cv::Mat& image);

/// std::invalid_argument naming both sizes when the image (or an image of width x height, as its
/// file's header says) is not the camera's size.
void RequireCameraSize(const cv::Mat& image, const CameraModel& camera);
void RequireCameraSize(int width, int height, const CameraModel& camera);

/// The samples of a skyline for the residual: every `stride` columns (at stride / 2, ...),
/// columns with confidence >= min_confidence, weight = confidence.
std::vector<SkylineSample> SkylineSamples(const Skyline& skyline,
                                          int stride,
                                          double min_confidence);

/// A camera frame's samples as the frontend takes them: the image checked against the camera's
/// size (RequireCameraSize), its skyline extracted from a segmentation mask or a photo as
/// `source` says ("mask", "image", or "auto": LooksLikeMask), a 4-channel photo taken as BGR,
/// then SkylineSamples. std::invalid_argument for a wrong size, a mask that is not 8-bit
/// single-channel, an unknown source, or what the extraction refuses.
std::vector<SkylineSample> FrameSamples(const cv::Mat& image,
                                        const CameraModel& camera,
                                        const std::string& source,
                                        int stride,
                                        double min_confidence);

}  // namespace skerry::skyline
