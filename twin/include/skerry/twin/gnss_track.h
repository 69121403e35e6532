#pragma once
/// \file
/// The truth of a GNSS-only recording (a marine logger's fixes at a few Hz, no IMU): a smoothed
/// track through the fixes, and the white noise of the fixes about it, so that the digital twin
/// can re-simulate the recording's GNSS (docs/twin.md).
///
/// Per axis of GnssFix::p_w (east, north, up in the local frame w), the continuous white-noise-
/// acceleration ("nearly constant velocity") model (Bar-Shalom, Li & Kirubarajan 2001,
/// "Estimation with Applications to Tracking and Navigation", sec. 6.2.2): the state [p, v] over
/// a step of dt seconds (any dt: gaps are fine)
///
///     x_k = F x_{k-1} + w,   F = [1 dt; 0 1],   w ~ N(0, Q),   Q = q [dt^3/3  dt^2/2; dt^2/2  dt]
///     z_k = p_k + n,         n ~ N(0, sigma^2)
///
/// with q the power spectral density of the acceleration (m^2/s^3) and sigma the fixes' white
/// noise (m). (q, sigma) are the maximum of the likelihood of the Kalman filter's innovations
/// (the prediction-error decomposition: Harvey 1989, "Forecasting, Structural Time Series Models
/// and the Kalman Filter", sec. 3.4; Shumway & Stoffer, "Time Series Analysis and Its
/// Applications", sec. 6.3), east and north pooled (one q and one sigma, the sum of the two axes'
/// log-likelihoods), up on its own, within q in [1e-4, 1e3] m^2/s^3 and sigma in [1e-3, 30] m.
/// The filter starts diffuse: the first two fixes give the state at the second exactly (position
/// the fix, velocity their difference over dt, with the covariance that follows from the model),
/// and their two innovations are left out of the likelihood, which is then the diffuse
/// likelihood (Harvey 1989, sec. 3.4). Since scaling q and sigma^2 together scales every
/// innovation variance alike, sigma^2 is concentrated out in closed form (Harvey 1989, sec. 3.4)
/// and the search is over r = q / sigma^2 alone: a log grid of 8 points a decade, then golden
/// section between the best point's neighbours.
///
/// The Rauch-Tung-Striebel smoother (Rauch, Tung & Striebel 1965, "Maximum likelihood estimates
/// of linear dynamic systems", AIAA J. 3(8)) at the ML (q, sigma) then gives position and
/// velocity at every fix; the first fix, outside the filter's proper start, from the second's
/// smoothed state through the model, conditioned on the first fix.
///
/// The 1-sigma of each ML sigma is from the curvature of the profile log-likelihood in log sigma
/// (q maximised at each sigma; the observed information, Pawitan 2001, "In All Likelihood",
/// ch. 3), by a central second difference: sd(sigma) = sigma / sqrt(-d2 logL / d(log sigma)^2).

#include <vector>

#include "skerry/core/measurements.h"
#include "skerry/core/nav_state.h"
#include "skerry/eval/identified_value.h"

namespace skerry {

struct GnssTrackOptions {
  /// Below this horizontal speed of the smoothed track the yaw is held (the last moving fix's;
  /// before the first moving fix, the first moving fix's; 0 when the track never moves).
  double min_speed_for_course_m_s = 0.5;
};

struct GnssTrack {
  /// One per fix, at the fix's stamp: p_w_b the smoothed position of the antenna taken as the
  /// body origin, v_w its smoothed velocity, q_w_b a pure yaw rotation with the body's x axis
  /// (FLU) along the course over ground (yaw = atan2(v_north, v_east), counter-clockwise from
  /// east), biases zero.
  std::vector<NavState> states;
  double accel_psd_horizontal = 0;           ///< q, m^2/s^3, ML (east and north)
  double accel_psd_vertical = 0;             ///< q, m^2/s^3, ML (up)
  IdentifiedValue white_sigma_horizontal_m;  ///< ML white noise per horizontal axis, m
  IdentifiedValue white_sigma_vertical_m;    ///< ML white noise of the up axis, m
  /// The maximised log-likelihood (horizontal plus vertical), fixes 3 onwards.
  double log_likelihood = 0;
};

/// Smooths `fixes` (their p_w) as described above. Throws std::invalid_argument for fewer than
/// 10 fixes, stamps that do not strictly increase, a non-finite position, or a negative or
/// non-finite min_speed_for_course_m_s.
GnssTrack SmoothGnssTrack(const std::vector<GnssFix>& fixes, const GnssTrackOptions& options = {});

}  // namespace skerry
