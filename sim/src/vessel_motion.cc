#include "skerry/sim/vessel_motion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "random.h"

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;

// The smooth step used for every ramp, on x in [0, 1]:
//   s(x) = x - sin(2 pi x) / (2 pi),  s(0) = 0, s(1) = 1,
//   s'(x) = 1 - cos(2 pi x),          zero at both ends,
//   s''(x) = 2 pi sin(2 pi x),        zero at both ends,
//   S(x) = int_0^x s = x^2 / 2 + (cos(2 pi x) - 1) / (4 pi^2),  S(1) = 1/2.
// A quantity ramped with s therefore has continuous first and second derivatives at the ends
// of the ramp, so speed, rate of turn and their rates join smoothly between legs.
double Step(double x) { return x - std::sin(2.0 * kPi * x) / (2.0 * kPi); }
double StepD1(double x) { return 1.0 - std::cos(2.0 * kPi * x); }
double StepD2(double x) { return 2.0 * kPi * std::sin(2.0 * kPi * x); }
double StepIntegral(double x) {
  return 0.5 * x * x + (std::cos(2.0 * kPi * x) - 1.0) / (4.0 * kPi * kPi);
}

struct WaveSum {
  double value = 0.0, d1 = 0.0, d2 = 0.0;
};

}  // namespace

VesselMotion::VesselMotion(const TrajectorySpec& trajectory,
                           const WaveSpec& waves,
                           double duration_s,
                           std::uint64_t seed)
    : start_enu_m_(trajectory.start_enu_m),
      current_enu_m_s_(trajectory.current_enu_m_s),
      heel_rad_per_m_s2_(trajectory.heel_deg_per_m_s2 * kDegToRad),
      table_step_s_(0.01) {
  if (!(duration_s > 0.0)) throw std::invalid_argument("VesselMotion: duration_s must be > 0");
  double t = 0.0;
  double u = trajectory.start_speed_m_s;
  double yaw = 0.5 * kPi - trajectory.start_heading_deg * kDegToRad;
  for (const Leg& leg : trajectory.legs) {
    if (t >= duration_s) break;  // legs past the end are cut
    Segment seg;
    seg.type = leg.type;
    seg.t0 = t;
    seg.u0 = u;
    seg.yaw0 = yaw;
    switch (leg.type) {
      case Leg::Type::kStraight:
        seg.t1 = t + leg.duration_s;
        break;
      case Leg::Type::kTurn: {
        const double ramp = leg.ramp_s < 0.0 ? trajectory.turn_ramp_s : leg.ramp_s;
        const double angle = std::abs(leg.angle_deg) * kDegToRad;
        const double rate = leg.rate_deg_s * kDegToRad;
        if (!(ramp > 0.0) || !(rate > 0.0)) {
          throw std::invalid_argument("VesselMotion: turn needs ramp_s > 0 and rate_deg_s > 0");
        }
        // Covered angle = peak * (ramp + hold); short turns never reach the requested rate.
        const double peak = std::min(rate, angle / ramp);
        seg.ramp_s = ramp;
        seg.hold_s = std::max(0.0, angle / std::max(peak, 1e-300) - ramp);
        // Starboard (heading increases) is negative ENU yaw rate.
        seg.r_peak = leg.angle_deg > 0.0 ? -peak : peak;
        seg.t1 = t + 2.0 * ramp + seg.hold_s;
        yaw -= leg.angle_deg * kDegToRad;
        break;
      }
      case Leg::Type::kSpeedChange: {
        if (!(leg.accel_m_s2 > 0.0) || leg.to_m_s < 0.0) {
          throw std::invalid_argument("VesselMotion: speed change needs accel > 0, to >= 0");
        }
        seg.du = leg.to_m_s - u;
        seg.t1 = t + std::abs(seg.du) / leg.accel_m_s2;
        u = leg.to_m_s;
        break;
      }
    }
    if (seg.t1 <= seg.t0) continue;  // zero-length manoeuvre
    segments_.push_back(seg);
    t = seg.t1;
  }
  Segment tail;  // straight on forever
  tail.t0 = t;
  tail.t1 = std::numeric_limits<double>::infinity();
  tail.u0 = u;
  tail.yaw0 = yaw;
  segments_.push_back(tail);

  Rng rng(seed, RngStream::kWavePhases);
  auto draw = [&rng](const std::vector<WaveComponent>& in, double scale, std::vector<Wave>* out) {
    for (const WaveComponent& c : in) {
      out->push_back({c.amplitude * scale, 2.0 * kPi / c.period_s, 2.0 * kPi * rng.Uniform()});
    }
  };
  draw(waves.roll_deg, kDegToRad, &roll_);
  draw(waves.pitch_deg, kDegToRad, &pitch_);
  draw(waves.heave_m, 1.0, &heave_);

  // Horizontal position table by Simpson's rule on the closed-form velocity. The velocity has
  // continuous derivatives up to the third, so the quadrature error is far below a micrometre.
  const auto n = static_cast<std::size_t>(std::ceil((duration_s + 2.0) / table_step_s_)) + 1;
  table_p_xy_.resize(n);
  table_p_xy_[0] = start_enu_m_.head<2>();
  for (std::size_t k = 1; k < n; ++k) {
    const double ta = static_cast<double>(k - 1) * table_step_s_;
    const double tb = static_cast<double>(k) * table_step_s_;
    table_p_xy_[k] = table_p_xy_[k - 1] +
                     (tb - ta) / 6.0 *
                         (HorizontalVelocity(ta) + 4.0 * HorizontalVelocity(0.5 * (ta + tb)) +
                          HorizontalVelocity(tb));
  }
}

const VesselMotion::Segment& VesselMotion::SegmentAt(double t_s) const {
  // Last segment whose t0 <= t_s (the first one for t_s < 0).
  auto it = std::upper_bound(segments_.begin(), segments_.end(), t_s,
                             [](double t, const Segment& s) { return t < s.t0; });
  if (it == segments_.begin()) return segments_.front();
  return *(it - 1);
}

VesselMotion::Profile VesselMotion::ProfileAt(double t_s) const {
  const Segment& seg = SegmentAt(t_s);
  const double tau = std::min(std::max(t_s - seg.t0, 0.0), seg.t1 - seg.t0);
  Profile p{seg.u0, 0.0, 0.0, 0.0, 0.0, 0.0, seg.yaw0};
  switch (seg.type) {
    case Leg::Type::kStraight:
      break;
    case Leg::Type::kSpeedChange: {
      const double len = seg.t1 - seg.t0;
      const double x = tau / len;
      p.u = seg.u0 + seg.du * Step(x);
      p.du = seg.du * StepD1(x) / len;
      p.ddu = seg.du * StepD2(x) / (len * len);
      break;
    }
    case Leg::Type::kTurn: {
      const double tr = seg.ramp_s;
      const double r = seg.r_peak;
      if (tau < tr) {  // ramp up
        const double x = tau / tr;
        p.r = r * Step(x);
        p.dr = r * StepD1(x) / tr;
        p.ddr = r * StepD2(x) / (tr * tr);
        p.yaw = seg.yaw0 + r * tr * StepIntegral(x);
      } else if (tau < tr + seg.hold_s) {  // steady turn
        p.r = r;
        p.yaw = seg.yaw0 + r * (0.5 * tr + (tau - tr));
      } else {  // ramp down
        const double x = std::min((tau - tr - seg.hold_s) / tr, 1.0);
        p.r = r * (1.0 - Step(x));
        p.dr = -r * StepD1(x) / tr;
        p.ddr = -r * StepD2(x) / (tr * tr);
        p.yaw = seg.yaw0 + r * (0.5 * tr + seg.hold_s + tr * (x - StepIntegral(x)));
      }
      break;
    }
  }
  return p;
}

Eigen::Vector2d VesselMotion::HorizontalVelocity(double t_s) const {
  const Profile p = ProfileAt(t_s);
  return p.u * Eigen::Vector2d(std::cos(p.yaw), std::sin(p.yaw)) + current_enu_m_s_;
}

BodyKinematics VesselMotion::At(double t_s) const {
  t_s = std::max(t_s, 0.0);
  const Profile pr = ProfileAt(t_s);

  auto sum = [t_s](const std::vector<Wave>& waves) {
    WaveSum s;
    for (const Wave& w : waves) {
      const double arg = w.omega_rad_s * t_s + w.phase_rad;
      s.value += w.amplitude * std::sin(arg);
      s.d1 += w.amplitude * w.omega_rad_s * std::cos(arg);
      s.d2 -= w.amplitude * w.omega_rad_s * w.omega_rad_s * std::sin(arg);
    }
    return s;
  };
  WaveSum roll = sum(roll_);
  const WaveSum pitch = sum(pitch_);
  const WaveSum heave = sum(heave_);
  // Heel proportional to the centripetal acceleration u * r (left turn: r > 0, acceleration
  // to +y; outward heel = starboard down = positive roll).
  roll.value += heel_rad_per_m_s2_ * pr.u * pr.r;
  roll.d1 += heel_rad_per_m_s2_ * (pr.du * pr.r + pr.u * pr.dr);
  roll.d2 += heel_rad_per_m_s2_ * (pr.ddu * pr.r + 2.0 * pr.du * pr.dr + pr.u * pr.ddr);

  BodyKinematics k;
  k.t_s = t_s;
  k.roll_rad = roll.value;
  k.pitch_rad = pitch.value;
  k.yaw_enu_rad = pr.yaw;
  k.speed_m_s = pr.u;

  // Position: table entry plus Simpson steps from it.
  const double step = table_step_s_;
  const auto last = static_cast<double>(table_p_xy_.size() - 1);
  const double kf = std::min(std::floor(t_s / step), last);
  Eigen::Vector2d p_xy = table_p_xy_[static_cast<std::size_t>(kf)];
  double ta = kf * step;
  while (ta < t_s) {
    const double tb = std::min(t_s, ta + step);
    p_xy += (tb - ta) / 6.0 *
            (HorizontalVelocity(ta) + 4.0 * HorizontalVelocity(0.5 * (ta + tb)) +
             HorizontalVelocity(tb));
    ta = tb;
  }
  const double cy = std::cos(pr.yaw);
  const double sy = std::sin(pr.yaw);
  k.p_w_b << p_xy, start_enu_m_.z() + heave.value;
  k.v_w << pr.u * cy + current_enu_m_s_.x(), pr.u * sy + current_enu_m_s_.y(), heave.d1;
  k.a_w << pr.du * cy - pr.u * pr.r * sy, pr.du * sy + pr.u * pr.r * cy, heave.d2;

  // Attitude R_w_b = Rz(yaw) Ry(pitch) Rx(roll). With R^T dR/dt = [omega_b]x:
  //   omega_b = [droll - dyaw sp,  dpitch cr + dyaw sr cp,  -dpitch sr + dyaw cr cp]
  // and alpha_b its time derivative.
  const double phi = roll.value, dphi = roll.d1, ddphi = roll.d2;
  const double th = pitch.value, dth = pitch.d1, ddth = pitch.d2;
  const double dpsi = pr.r, ddpsi = pr.dr;
  const double sr = std::sin(phi), cr = std::cos(phi);
  const double sp = std::sin(th), cp = std::cos(th);
  k.q_w_b = Eigen::AngleAxisd(pr.yaw, Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(th, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitX());
  k.q_w_b.normalize();
  k.omega_b << dphi - dpsi * sp, dth * cr + dpsi * sr * cp, -dth * sr + dpsi * cr * cp;
  k.alpha_b << ddphi - ddpsi * sp - dpsi * cp * dth,
      ddth * cr - dth * sr * dphi + ddpsi * sr * cp + dpsi * (cr * dphi * cp - sr * sp * dth),
      -ddth * sr - dth * cr * dphi + ddpsi * cr * cp + dpsi * (-sr * dphi * cp - cr * sp * dth);
  return k;
}

}  // namespace skerry::sim
