#pragma once
/// \file
/// A camera's orientation from ground control points, its centre known: the check of the camera
/// model, the map frame and the DEM reader on a real photo (Engabreen, docs/results.md).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "skerry/skyline/camera_model.h"

namespace skerry::skyline {

/// One row of a GCP file: map coordinates (e.g. UTM east, north, height) and the pixel.
struct GcpRow {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  int line = 0;
};

/// Reads `X Y Z u v` rows; lines starting with % or # are comments; a pixel coordinate may be
/// written as a sum (ImGRAFT's `1951+9`). InputError naming the file, line and field for a
/// malformed or non-finite value or a row of another length; an empty file is an error too.
std::vector<GcpRow> ReadGcpFile(const std::string& path);

struct CameraRotationFit {
  Eigen::Quaterniond q_w_c = Eigen::Quaterniond::Identity();
  double focal_px = 0.0;  ///< the fitted focal length (the camera's if not fitted)
  double k1 = 0.0;        ///< the fitted radial distortion (0 if not fitted)
  double rms_px = 0.0;    ///< reprojection RMS over the points
  bool converged = false;
};

/// The rotation R_w_c (and, with fit_focal, one focal length for fx and fy; with fit_k1, a
/// radial distortion k1 about the camera's principal point) that projects the points (ENU) onto
/// their pixels from the known centre p_w_c, by Levenberg-Marquardt from `start`.
CameraRotationFit FitCameraRotation(const CameraModel& camera,
                                    const Eigen::Vector3d& p_w_c,
                                    const std::vector<Eigen::Vector3d>& points_w,
                                    const std::vector<Eigen::Vector2d>& pixels,
                                    const Eigen::Quaterniond& start,
                                    bool fit_focal,
                                    bool fit_k1 = false);

}  // namespace skerry::skyline
