#pragma once
/// \file
/// Heading for people: degrees clockwise from north, in [0, 360). World is local ENU and the body
/// is FLU, so the heading of a body vector is atan2(east, north) of that vector in the world.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "skerry/core/earth_model.h"

namespace skerry {

/// Heading (rad, clockwise from north, in (-pi, pi]) of the body x axis.
double HeadingRad(const Eigen::Quaterniond& q_w_b);

/// Heading (deg, clockwise from north, in [0, 360)) of the body x axis.
double HeadingDeg(const Eigen::Quaterniond& q_w_b);

/// Heading (deg, clockwise from the local north at p_w, in [0, 360)) of the body x axis, for
/// people at a place away from the world's origin: w's north is north at the origin only. Away
/// from it the meridians converge, by the difference of longitude times sin(latitude) (0.13 deg
/// 15 km east of the origin at 45 deg N: Snyder 1987, "Map Projections: A Working Manual", the
/// convergence of the meridians), and the vertical tilts (EarthModel::LocalLevel). The flat
/// Earth's north is w's everywhere.
double HeadingDegAt(const EarthModel& earth,
                    const Eigen::Vector3d& p_w,
                    const Eigen::Quaterniond& q_w_b);

/// Rotation world<-body for given roll, pitch (rad, FLU body: roll about x, pitch about y with
/// positive pitch = nose DOWN in FLU, i.e. right-handed about y) and heading (rad, clockwise from
/// north). R = Rz(yaw_enu) Ry(pitch) Rx(roll), yaw_enu = pi/2 - heading.
Eigen::Quaterniond QuaternionFromRollPitchHeading(double roll_rad,
                                                  double pitch_rad,
                                                  double heading_rad);

}  // namespace skerry
