#include "skerry/core/heading.h"

#include <cmath>

namespace skerry {

double HeadingRad(const Eigen::Quaterniond& q_w_b) {
  // Body x axis in the world (ENU); heading is measured from north (y) towards east (x).
  const Eigen::Vector3d x_w = q_w_b * Eigen::Vector3d::UnitX();
  double heading = std::atan2(x_w.x(), x_w.y());
  if (heading <= -M_PI) heading += 2.0 * M_PI;  // atan2 may return -pi; the range is (-pi, pi]
  return heading;
}

double HeadingDeg(const Eigen::Quaterniond& q_w_b) {
  double deg = HeadingRad(q_w_b) * 180.0 / M_PI;
  if (deg < 0.0) deg += 360.0;
  if (deg >= 360.0) deg -= 360.0;  // -tiny + 360 can round to 360
  return deg;
}

double HeadingDegAt(const EarthModel& earth,
                    const Eigen::Vector3d& p_w,
                    const Eigen::Quaterniond& q_w_b) {
  // The body in the local-level ENU frame n at p_w: q_n_b = R_w_n^T q_w_b.
  const Eigen::Quaterniond q_w_n(earth.LocalLevel(p_w));
  return HeadingDeg(q_w_n.conjugate() * q_w_b);
}

Eigen::Quaterniond QuaternionFromRollPitchHeading(double roll_rad,
                                                  double pitch_rad,
                                                  double heading_rad) {
  const double yaw_enu = M_PI / 2.0 - heading_rad;
  const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw_enu, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX());
  return q.normalized();
}

}  // namespace skerry
