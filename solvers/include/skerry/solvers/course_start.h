#pragma once
/// \file
/// The heading at the first of a run of fixes from their course over ground, with the turns the
/// gyro saw along the way taken out (init.mode cog and auto).
///
/// The chord from the first fix to one min_cog_distance_m away points along the mean course over
/// the stretch, not along the heading at its start: a rover that turns 40 deg over those 15 m
/// starts 20 deg off (the Husky recording did, with 5 deg claimed). Over a few seconds the gyro
/// knows the turn well, so each fix-to-fix displacement is rotated back by the heading change the
/// gyro integrated up to its middle, and the rotated displacements are summed:
///   h_0 = arg( sum_k (dN_k + i dE_k) exp(i dpsi_k) ),
/// with h clockwise from north and dpsi_k the counter-clockwise turn about the vertical from the
/// first fix to the middle of displacement k. A straight stretch gives back the chord. Its sigma
/// combines the end fixes' noise across the straightened length and the gyro's bias prior over
/// the mean time along it; like the chord, it takes the course for the heading (no crab or
/// sideslip: init.yaw_sigma_deg covers those).

#include <Eigen/Core>
#include <vector>

#include "skerry/core/time.h"

namespace skerry {

struct CourseFix {
  TimeNs t_ns = 0;
  Eigen::Vector2d en_m = Eigen::Vector2d::Zero();  ///< east, north in the first fix's local level
};

struct YawRate {
  TimeNs t_ns = 0;
  double rad_s = 0.0;  ///< counter-clockwise about the local vertical
};

struct CourseStart {
  double heading_rad = 0.0;  ///< at the first fix, clockwise from north
  double speed_m_s = 0.0;    ///< straightened length over the stretch's duration
  double sigma_rad = 0.0;    ///< from fix noise and the gyro bias prior (not crab)
  double turned_rad = 0.0;   ///< what the gyro turned through from the first fix to the last
};

/// `fixes`: two or more, in time order. `rates`: in time order, covering the fixes' span (rates
/// outside it are ignored; the turn is held before the first rate). `sigma_horizontal_m`: one
/// fix's horizontal sigma; `gyro_bias_sigma_rad_s`: the prior on the bias about the vertical.
CourseStart CourseAtFirstFix(const std::vector<CourseFix>& fixes,
                             const std::vector<YawRate>& rates,
                             double sigma_horizontal_m,
                             double gyro_bias_sigma_rad_s);

}  // namespace skerry
