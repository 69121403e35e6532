#include "skerry/solvers/rest_detection.h"

#include <algorithm>
#include <cmath>

namespace skerry {

RestPeriod DetectRestAtStart(const std::vector<ImuSample>& imu,
                             const ImuConfig& config,
                             double gravity_m_s2) {
  RestPeriod rest;
  if (imu.size() < 2) return rest;
  const TimeNs t0 = imu.front().t_ns;
  const TimeNs block_ns = SecondsToNs(kRestBlockS);
  const double n_block = std::max(1.0, kRestBlockS * config.rate_hz);
  // Standard error of a block mean under white noise: density sqrt(rate) / sqrt(n).
  const double tol_g = std::max(
      4.0 * config.noise.gyro_noise_density_rad_s_sqrt_hz * std::sqrt(config.rate_hz / n_block),
      0.3 * M_PI / 180.0);
  const double tol_a = std::max(
      4.0 * config.noise.accel_noise_density_m_s2_sqrt_hz * std::sqrt(config.rate_hz / n_block),
      0.1);
  Eigen::Vector3d first_g = Eigen::Vector3d::Zero(), first_a = Eigen::Vector3d::Zero();
  bool have_first = false;  // the first block with samples is the reference (a gap may precede it)
  size_t k = 0;
  for (int block = 0;; ++block) {
    const TimeNs begin = t0 + block * block_ns, end = begin + block_ns;
    if (NsToSeconds(begin - t0) >= kRestMaxS) {
      rest.decided = true;
      rest.duration_s = kRestMaxS;
      return rest;
    }
    if (imu.back().t_ns < end) return rest;  // this block is not complete yet: undecided
    Eigen::Vector3d g = Eigen::Vector3d::Zero(), a = Eigen::Vector3d::Zero();
    int n = 0;
    for (; k < imu.size() && imu[k].t_ns < end; ++k) {
      g += imu[k].gyro_rad_s;
      a += imu[k].accel_m_s2;
      ++n;
    }
    if (n == 0) continue;
    g /= n;
    a /= n;
    const bool gravity = std::abs(a.norm() - gravity_m_s2) < 0.05 * gravity_m_s2;
    if (!have_first) {
      first_g = g;
      first_a = a;
      have_first = true;
    }
    if (!gravity || (g - first_g).cwiseAbs().maxCoeff() > tol_g ||
        (a - first_a).cwiseAbs().maxCoeff() > tol_a) {
      rest.decided = true;
      const double duration = NsToSeconds(begin - t0);
      rest.duration_s = duration >= kRestMinS ? duration : 0.0;
      return rest;
    }
  }
}

}  // namespace skerry
