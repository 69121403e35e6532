#pragma once
/// \file
/// Where an aerial photograph shows a structure's outline: not where the structure stands.
///
/// A frame camera at C looks down; the photograph is rectified onto a terrain model, which
/// leaves out boats, buildings and cranes and cannot follow the vertical face of a quay. The top
/// outline of a structure standing from z_floor (the water at a quay's foot) to z_top is seen along
/// rays that meet the rectification surface further from the nadir, so the photograph shows it
/// displaced away from the nadir by
///
///   d = (z_top - z_floor) / (C_z - z_top) * (x - C_xy)               (relief displacement)
///
/// (Wolf and Dewitt, "Elements of Photogrammetry", sec. 6-8, eq. 6-11: a point h above the datum
/// at radius r from the nadir moves by h r / (H - h)). At 150 m from the nadir of a photograph
/// taken from 800 m, a quay's 1.8 m edge moves 0.34 m and a 10 m building's roof line 1.9 m: the
/// size of the alignment's whole error budget.
///
/// A face turned towards the camera shows its foot too, at the true position. The model still
/// takes the top outline for every face: a LiDAR's edge points in a harbour are mostly moored
/// hulls, buildings and cranes, none of them in any terrain model, whose strong edge in the image
/// is the top's (the deck's, the roof's). On the simulated harbour, displacing only faces turned
/// away from the camera left 0.37 m of across-track bias per scan; displacing all left none
/// (docs/lidar_aerial.md, bench/harbour_scan_fixes.cc).
///
/// The image point of an edge point x is u = x + k (x - C_xy), k from ReliefFactor.

#include <Eigen/Core>

namespace skerry::lidar_aerial {

/// k for an edge point of a structure standing from floor_w to top_w (ENU heights), in a
/// photograph taken from viewpoint_w (ENU); 0 for nothing standing, or a viewpoint not above it.
inline double ReliefFactor(const Eigen::Vector3d& viewpoint_w, double top_w, double floor_w) {
  const double rise = top_w - floor_w;
  const double above = viewpoint_w.z() - top_w;
  if (!(rise > 0.0) || !(above > 1.0)) return 0.0;
  return rise / above;
}

}  // namespace skerry::lidar_aerial
