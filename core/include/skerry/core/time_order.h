#pragma once
/// \file
/// The order in which recorded IMU samples and GNSS fixes reach an estimator: by time, and on
/// equal times the IMU sample first, as a fix is received after the IMU sample of its epoch.
/// One rule for every replay (RunWindow, the yaw-hypothesis bank's buffers, tests).

#include <cstddef>

namespace skerry {

/// Calls `on_imu(sample)` and `on_gnss(fix)` for every element of the two time-ordered
/// sequences, merged by that rule; fixes after the last sample come last.
template <typename ImuRange, typename GnssRange, typename OnImu, typename OnGnss>
void ForEachInTimeOrder(const ImuRange& imu,
                        const GnssRange& gnss,
                        OnImu&& on_imu,
                        OnGnss&& on_gnss) {
  auto g = gnss.begin();
  for (const auto& sample : imu) {
    for (; g != gnss.end() && g->t_ns < sample.t_ns; ++g) on_gnss(*g);
    on_imu(sample);
  }
  for (; g != gnss.end(); ++g) on_gnss(*g);
}

}  // namespace skerry
