#include "skerry/sim/earth_motion.h"

#include <GeographicLib/Constants.hpp>
#include <cmath>

#include "skerry/core/so3.h"

namespace skerry::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// WGS84 meridian (M) and prime-vertical (N) radii of curvature at latitude `lat` (rad).
void Radii(double lat, double* M, double* N) {
  const double a = GeographicLib::Constants::WGS84_a();
  const double f = GeographicLib::Constants::WGS84_f();
  const double e2 = f * (2.0 - f);
  const double s = std::sin(lat);
  const double w2 = 1.0 - e2 * s * s;
  *N = a / std::sqrt(w2);
  *M = a * (1.0 - e2) / (w2 * std::sqrt(w2));
}

}  // namespace

EarthMotion::EarthMotion(const VesselMotion& motion,
                         const GeoOrigin& origin,
                         const EarthConfig& earth,
                         double duration_s)
    : motion_(motion), origin_(origin), field_(origin, earth) {
  if (!field_.round()) return;

  // Start: below the start point of the trajectory, on the origin's height plus heave.
  const BodyKinematics k0 = motion_.At(0.0);
  const Eigen::Vector3d llh0 = field_.ToGeodetic(Eigen::Vector3d(k0.p_w_b.x(), k0.p_w_b.y(), 0.0));
  const double lat0 = llh0.x(), lon0 = llh0.y();
  const auto n = static_cast<std::size_t>(std::ceil((duration_s + 2.0) / table_step_s_)) + 1;
  table_lat_lon_rad_.resize(n);
  table_lat_lon_rad_[0] = Eigen::Vector2d(lat0 * kDeg, lon0 * kDeg);
  for (std::size_t k = 1; k < n; ++k) {
    const double t = static_cast<double>(k - 1) * table_step_s_;
    const double h = table_step_s_;
    const Eigen::Vector2d& y = table_lat_lon_rad_[k - 1];
    const Eigen::Vector2d d1 = LatLonRate(t, y);
    const Eigen::Vector2d d2 = LatLonRate(t + h / 2, y + h / 2 * d1);
    const Eigen::Vector2d d3 = LatLonRate(t + h / 2, y + h / 2 * d2);
    const Eigen::Vector2d d4 = LatLonRate(t + h, y + h * d3);
    table_lat_lon_rad_[k] = y + h / 6 * (d1 + 2 * d2 + 2 * d3 + d4);
  }
}

EarthMotion::~EarthMotion() = default;

Eigen::Vector2d EarthMotion::LatLonRate(double t_s, const Eigen::Vector2d& lat_lon) const {
  const BodyKinematics k = motion_.At(t_s);
  const double h = origin_.height_m + k.p_w_b.z();
  double M, N;
  Radii(lat_lon[0], &M, &N);
  return Eigen::Vector2d(k.v_w.y() / (M + h), k.v_w.x() / ((N + h) * std::cos(lat_lon[0])));
}

Eigen::Vector2d EarthMotion::LatLonAt(double t_s) const {
  const double step = table_step_s_;
  const auto last = static_cast<double>(table_lat_lon_rad_.size() - 1);
  const double kf = std::min(std::floor(std::max(t_s, 0.0) / step), last);
  Eigen::Vector2d y = table_lat_lon_rad_[static_cast<std::size_t>(kf)];
  const double t0 = kf * step;
  const double h = t_s - t0;
  if (h <= 0.0) return y;
  const Eigen::Vector2d d1 = LatLonRate(t0, y);
  const Eigen::Vector2d d2 = LatLonRate(t0 + h / 2, y + h / 2 * d1);
  const Eigen::Vector2d d3 = LatLonRate(t0 + h / 2, y + h / 2 * d2);
  const Eigen::Vector2d d4 = LatLonRate(t0 + h, y + h * d3);
  return y + h / 6 * (d1 + 2 * d2 + 2 * d3 + d4);
}

EarthKinematics EarthMotion::At(double t_s) const {
  EarthKinematics out;
  const BodyKinematics local = motion_.At(t_s);
  out.q_n_b = local.q_w_b;
  if (!field_.round()) {
    out.body = local;
    out.height_m = origin_.height_m + local.p_w_b.z();
    return out;
  }
  const Eigen::Vector2d ll = LatLonAt(t_s);
  const double lat = ll[0];
  const double h = origin_.height_m + local.p_w_b.z();
  out.lat_deg = lat / kDeg;
  out.lon_deg = ll[1] / kDeg;
  out.height_m = h;
  const Eigen::Vector3d p = field_.FromGeodetic(out.lat_deg, out.lon_deg, h, &out.R_w_n);

  double M, N;
  Radii(lat, &M, &N);
  const Eigen::Vector3d& v_n = local.v_w;  // velocity over ground in n (east, north, up)
  const Eigen::Vector3d& a_n = local.a_w;  // its rate of change in n
  const double tan_lat = std::tan(lat);
  const Eigen::Vector3d omega_en(-v_n.y() / (M + h), v_n.x() / (N + h),
                                 v_n.x() * tan_lat / (N + h));
  // d(omega_en)/dt, dropping the terms in dM/dt, dN/dt and dh/dt (v h' / R^2 ~ 1e-13 rad/s^2).
  const double lat_rate = v_n.y() / (M + h);
  const Eigen::Vector3d omega_en_dot(
      -a_n.y() / (M + h), a_n.x() / (N + h),
      (a_n.x() * tan_lat + v_n.x() * lat_rate / (std::cos(lat) * std::cos(lat))) / (N + h));

  const Eigen::Matrix3d R_n_b = local.q_w_b.toRotationMatrix();
  BodyKinematics& b = out.body;
  b = local;
  b.p_w_b = p;
  b.v_w = out.R_w_n * v_n;
  b.a_w = out.R_w_n * (a_n + omega_en.cross(v_n));
  b.q_w_b = Eigen::Quaterniond(out.R_w_n * R_n_b).normalized();
  const Eigen::Vector3d omega_en_b = R_n_b.transpose() * omega_en;
  b.omega_b = local.omega_b + omega_en_b;
  b.alpha_b = local.alpha_b + R_n_b.transpose() * omega_en_dot - local.omega_b.cross(omega_en_b);
  return out;
}

ImuSample IdealImu(const BodyKinematics& kin,
                   const Eigen::Quaterniond& q_b_i,
                   const Eigen::Vector3d& p_b_i,
                   const Eigen::Vector3d& omega_ie_w,
                   const Eigen::Vector3d& g_w_imu) {
  const Eigen::Matrix3d R_w_b = kin.q_w_b.toRotationMatrix();
  const Eigen::Matrix3d R_b_i = q_b_i.toRotationMatrix();
  const Eigen::Matrix3d R_w_i = R_w_b * R_b_i;
  const Eigen::Vector3d& w = kin.omega_b;
  const Eigen::Vector3d v_w_i = kin.v_w + R_w_b * w.cross(p_b_i);
  const Eigen::Vector3d a_w_i =
      kin.a_w + R_w_b * (kin.alpha_b.cross(p_b_i) + w.cross(w.cross(p_b_i)));
  ImuSample s;
  s.t_ns = SecondsToNs(kin.t_s);
  s.gyro_rad_s = R_b_i.transpose() * (w + R_w_b.transpose() * omega_ie_w);
  s.accel_m_s2 = R_w_i.transpose() * (a_w_i + 2.0 * omega_ie_w.cross(v_w_i) - g_w_imu);
  return s;
}

}  // namespace skerry::sim
