#include "skerry/solvers/measurement_checks.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "skerry/io/csv_reader.h"  // FormatSeconds

namespace skerry {

namespace {

[[noreturn]] void Refuse(const char* sensor, TimeNs t_ns, const std::string& what) {
  throw std::invalid_argument(std::string(sensor) + " at t=" + FormatSeconds(t_ns) + ": " + what);
}

}  // namespace

void CheckImuSample(const ImuSample& s) {
  if (!s.gyro_rad_s.allFinite()) Refuse("IMU sample", s.t_ns, "gyro value not finite");
  if (!s.accel_m_s2.allFinite()) Refuse("IMU sample", s.t_ns, "accelerometer value not finite");
}

void CheckGnssFix(const GnssFix& f) {
  if (!f.p_w.allFinite() || !std::isfinite(f.lat_deg) || !std::isfinite(f.lon_deg) ||
      !std::isfinite(f.height_m)) {
    Refuse("GNSS fix", f.t_ns, "position not finite");
  }
  for (int i = 0; i < 3; ++i) {
    if (!(f.sigma_enu_m[i] > 0.0) || !std::isfinite(f.sigma_enu_m[i])) {
      Refuse("GNSS fix", f.t_ns,
             "sigma_" + std::string(1, "enu"[i]) +
                 " must be finite and positive (the covariance is not positive definite)");
    }
  }
  if (f.has_heading) {
    if (!std::isfinite(f.heading_deg)) Refuse("GNSS fix", f.t_ns, "heading not finite");
    if (!(f.sigma_heading_deg > 0.0) || !std::isfinite(f.sigma_heading_deg)) {
      Refuse("GNSS fix", f.t_ns, "heading sigma must be finite and positive");
    }
  }
}

}  // namespace skerry
