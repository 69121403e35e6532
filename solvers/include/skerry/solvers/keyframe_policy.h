#pragma once
/// \file
/// Where keyframes go, for the sliding window and the batch smoother alike.
///
/// - The fixed grid, for IMU + GNSS: a keyframe at the first IMU sample at or past each multiple
///   of the period after the start (keyframe_rate_hz).
/// - Every sensor measurement (sensor_block.h) at time t gets a keyframe at t exactly, the IMU
///   preintegration split there with a sample interpolated linearly between its neighbours, as
///   visual-inertial systems key camera frames (Forster et al. 2017, sec. VI; OKVIS). A
///   measurement within merge_tolerance of a keyframe goes on that keyframe instead (1 ms: a
///   vessel at 10 m/s moves 1 cm), and a grid keyframe within min_gap after a measurement's
///   keyframe is skipped. A measurement shortly after a grid keyframe (more than the tolerance)
///   still gets its own: its time is what it measured.

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "skerry/core/measurements.h"
#include "skerry/core/time.h"

namespace skerry {

class KeyframePolicy {
 public:
  /// The shortest keyframe period (a microsecond: above any IMU's rate) and so the highest
  /// rate; the lowest is 1 / kMaxDurationS.
  static constexpr double kMinPeriodS = 1e-6;

  /// Throws std::invalid_argument unless 1 / kMaxDurationS <= rate_hz <= 1 / kMinPeriodS.
  explicit KeyframePolicy(double rate_hz)
      : period_ns_(PeriodNs(rate_hz)),
        merge_tolerance_ns_(std::min<TimeNs>(1'000'000, period_ns_ / 10)),
        min_gap_ns_(period_ns_ / 4) {}

  /// The first keyframe is at t0.
  void Start(TimeNs t0) { next_grid_ns_ = t0 + period_ns_; }
  /// True when an IMU sample at t closes a grid keyframe.
  bool GridDue(TimeNs t) const { return t + period_ns_ / 1000 >= next_grid_ns_; }
  /// A keyframe closed at t: on the grid, or for a measurement.
  void Closed(TimeNs t, bool on_grid) {
    if (on_grid) {
      next_grid_ns_ += period_ns_;
      if (next_grid_ns_ <= t) next_grid_ns_ = t + period_ns_;
    } else {
      while (next_grid_ns_ < t + min_gap_ns_) next_grid_ns_ += period_ns_;
    }
  }
  /// A measurement at t goes on the keyframe at keyframe_t (no keyframe of its own).
  bool Merges(TimeNs t, TimeNs keyframe_t) const {
    return std::abs(t - keyframe_t) <= merge_tolerance_ns_;
  }
  TimeNs period_ns() const { return period_ns_; }
  TimeNs merge_tolerance_ns() const { return merge_tolerance_ns_; }

 private:
  static TimeNs PeriodNs(double rate_hz) {
    if (!(rate_hz >= 1.0 / kMaxDurationS && rate_hz <= 1.0 / kMinPeriodS)) {
      throw std::invalid_argument("keyframe_rate_hz must be between 1e-09 and 1e+06 Hz, is " +
                                  std::to_string(rate_hz));
    }
    return SecondsToNs(1.0 / rate_hz);
  }

  TimeNs period_ns_;
  TimeNs merge_tolerance_ns_;
  TimeNs min_gap_ns_;
  TimeNs next_grid_ns_ = 0;
};

/// The IMU sample at t (a <= t <= b), linearly interpolated between a and b.
inline ImuSample InterpolateSample(const ImuSample& a, const ImuSample& b, TimeNs t) {
  if (b.t_ns == a.t_ns) return b;
  const double s = static_cast<double>(t - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  ImuSample m;
  m.t_ns = t;
  m.gyro_rad_s = a.gyro_rad_s + s * (b.gyro_rad_s - a.gyro_rad_s);
  m.accel_m_s2 = a.accel_m_s2 + s * (b.accel_m_s2 - a.accel_m_s2);
  return m;
}

}  // namespace skerry
