#include "skerry/sim/spline_motion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "skerry/core/so3.h"

namespace skerry::sim {
namespace {

// Uniform cubic B-spline basis at u in [0, 1] and its first and second derivatives in u
// (de Boor 1978; Qin 2000, "General matrix representations for B-splines", eq. 5).
void Basis(double u, double b[4], double db[4], double ddb[4]) {
  const double u2 = u * u, u3 = u2 * u, w = 1.0 - u;
  b[0] = w * w * w / 6.0;
  b[1] = (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0;
  b[2] = (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0;
  b[3] = u3 / 6.0;
  db[0] = -0.5 * w * w;
  db[1] = 0.5 * (3.0 * u2 - 4.0 * u);
  db[2] = 0.5 * (-3.0 * u2 + 2.0 * u + 1.0);
  db[3] = 0.5 * u2;
  ddb[0] = w;
  ddb[1] = 3.0 * u - 2.0;
  ddb[2] = 1.0 - 3.0 * u;
  ddb[3] = u;
}

// The cumulative basis B~_j = sum_{i >= j} B_i for j = 1..3 and its derivatives (Sommer et al.
// 2020, eq. 4: the matrix C of the uniform cubic case).
void CumulativeBasis(double u, double b[3], double db[3], double ddb[3]) {
  const double u2 = u * u, u3 = u2 * u;
  b[0] = (5.0 + 3.0 * u - 3.0 * u2 + u3) / 6.0;
  b[1] = (1.0 + 3.0 * u + 3.0 * u2 - 2.0 * u3) / 6.0;
  b[2] = u3 / 6.0;
  db[0] = 0.5 * (1.0 - u) * (1.0 - u);
  db[1] = 0.5 * (1.0 + 2.0 * u - 2.0 * u2);
  db[2] = 0.5 * u2;
  ddb[0] = u - 1.0;
  ddb[1] = 1.0 - 2.0 * u;
  ddb[2] = u;
}

// The rotation of the cumulative spline whose four control rotations are r[0..3], at u, with the
// body rate and its derivative (in units of 1/knot and 1/knot^2) when asked. R(u) = r0 prod_j
// Exp(B~_j d_j), d_j = Log(r_{j-1}^T r_j); recursively omega_j = A_j^T omega_{j-1} + B~'_j d_j
// and alpha_j = A_j^T alpha_{j-1} + B~''_j d_j + (A_j^T omega_{j-1}) x (B~'_j d_j) (Sommer et al.
// 2020, eq. 38-39, with R_j = R_{j-1} A_j).
Eigen::Quaterniond CumulativeRotation(const Eigen::Quaterniond* r,
                                      double u,
                                      Eigen::Vector3d* omega,
                                      Eigen::Vector3d* alpha) {
  double b[3], db[3], ddb[3];
  CumulativeBasis(u, b, db, ddb);
  Eigen::Quaterniond q = r[0];
  Eigen::Vector3d w = Eigen::Vector3d::Zero(), a = Eigen::Vector3d::Zero();
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector3d d = LogQ(Eigen::Quaterniond(r[j].conjugate() * r[j + 1]));
    const Eigen::Quaterniond A = ExpQ(Eigen::Vector3d(b[j] * d));
    const Eigen::Matrix3d At = A.conjugate().toRotationMatrix();
    const Eigen::Vector3d w_rot = At * w;
    a = At * a + ddb[j] * d + w_rot.cross(db[j] * d);
    w = w_rot + db[j] * d;
    q = q * A;
  }
  if (omega != nullptr) *omega = w;
  if (alpha != nullptr) *alpha = a;
  return q.normalized();
}

}  // namespace

SplineMotion::SplineMotion(const std::vector<NavState>& states, double knot_s) {
  if (states.size() < 2) {
    throw std::invalid_argument("SplineMotion: needs at least 2 states, got " +
                                std::to_string(states.size()));
  }
  std::vector<double> gaps;
  for (size_t i = 0; i < states.size(); ++i) {
    const NavState& s = states[i];
    if (!s.p_w_b.allFinite() || !s.v_w.allFinite() || !s.q_w_b.coeffs().allFinite() ||
        std::abs(s.q_w_b.norm() - 1.0) > 1e-6) {
      throw std::invalid_argument("SplineMotion: state " + std::to_string(i) +
                                  " is not finite or its quaternion not of unit norm");
    }
    if (i > 0) {
      if (s.t_ns <= states[i - 1].t_ns) {
        throw std::invalid_argument("SplineMotion: state " + std::to_string(i) +
                                    ": time does not increase");
      }
      gaps.push_back(NsToSeconds(s.t_ns - states[i - 1].t_ns));
    }
  }
  if (!(knot_s >= 0.0) || !std::isfinite(knot_s)) {
    throw std::invalid_argument("SplineMotion: knot spacing must be >= 0");
  }
  if (knot_s == 0.0) {
    std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
    knot_s = gaps[gaps.size() / 2];
  }
  start_ns_ = states.front().t_ns;
  end_ns_ = states.back().t_ns;
  const double span = NsToSeconds(end_ns_ - start_ns_);
  const int n = std::max(2, static_cast<int>(std::lround(span / knot_s)) + 1);  // knots
  h_ = span / (n - 1);

  // --- Knot targets: Hermite position, slerped rotation, between the bracketing states. ----
  std::vector<Eigen::Vector3d> P(n);
  std::vector<Eigen::Quaterniond> Q(n);
  size_t i = 0;
  for (int k = 0; k < n; ++k) {
    const TimeNs t = k == n - 1 ? end_ns_ : start_ns_ + SecondsToNs(k * h_);
    while (i + 2 < states.size() && states[i + 1].t_ns <= t) ++i;
    const NavState& a = states[i];
    const NavState& b = states[i + 1];
    const double dt = NsToSeconds(b.t_ns - a.t_ns);
    const double s = std::clamp(NsToSeconds(t - a.t_ns) / dt, 0.0, 1.0);
    const double s2 = s * s, s3 = s2 * s;
    P[k] = (2 * s3 - 3 * s2 + 1) * a.p_w_b + (s3 - 2 * s2 + s) * dt * a.v_w +
           (-2 * s3 + 3 * s2) * b.p_w_b + (s3 - s2) * dt * b.v_w;
    Q[k] = a.q_w_b.slerp(s, b.q_w_b).normalized();
    if (k > 0 && Q[k].dot(Q[k - 1]) < 0.0) Q[k].coeffs() *= -1.0;
  }

  // --- Position: interpolating B-spline with clamped end velocities. Unknowns c_0..c_{n-1};
  // c_{-1} = c_1 - 2h v_0 and c_n = c_{n-2} + 2h v_end (p'(t_k) = (c_{k+1} - c_{k-1}) / 2h).
  const Eigen::Vector3d v0 = states.front().v_w, v1 = states.back().v_w;
  std::vector<double> lower(n, 1.0 / 6), diag(n, 4.0 / 6), upper(n, 1.0 / 6);
  std::vector<Eigen::Vector3d> rhs = P;
  upper[0] = 2.0 / 6;
  rhs[0] += 2.0 * h_ * v0 / 6.0;
  lower[n - 1] = 2.0 / 6;
  rhs[n - 1] -= 2.0 * h_ * v1 / 6.0;
  // Thomas algorithm (diagonally dominant: stable without pivoting).
  for (int k = 1; k < n; ++k) {
    const double m = lower[k] / diag[k - 1];
    diag[k] -= m * upper[k - 1];
    rhs[k] -= m * rhs[k - 1];
  }
  std::vector<Eigen::Vector3d> c(n);
  c[n - 1] = rhs[n - 1] / diag[n - 1];
  for (int k = n - 2; k >= 0; --k) c[k] = (rhs[k] - upper[k] * c[k + 1]) / diag[k];
  c_.resize(n + 2);
  for (int k = 0; k < n; ++k) c_[k + 1] = c[k];
  c_[0] = c[1] - 2.0 * h_ * v0;
  c_[n + 1] = c[n - 2] + 2.0 * h_ * v1;

  // --- Rotation: control rotations corrected until the curve passes through Q_k. At a knot
  // (u = 0) the curve is r_{k-1} Exp(5/6 d_1) Exp(1/6 d_2), a local average with weights
  // (1/6, 4/6, 1/6); a step of 1.5 makes the fixed-point iteration contract by 1/2 per pass.
  r_.resize(n + 2);
  for (int k = 0; k < n; ++k) r_[k + 1] = Q[k];
  auto extend_ends = [this, n]() {
    r_[0] = r_[1] * ExpQ(Eigen::Vector3d(-LogQ(Eigen::Quaterniond(r_[1].conjugate() * r_[2]))));
    r_[n + 1] = r_[n] * ExpQ(LogQ(Eigen::Quaterniond(r_[n - 1].conjugate() * r_[n])));
  };
  extend_ends();
  std::vector<Eigen::Vector3d> step(n);
  for (int iteration = 0; iteration < 60; ++iteration) {
    double worst = 0.0;
    for (int k = 0; k < n; ++k) {
      // Knot k starts segment k (u = 0); the last knot ends segment n - 2 (u = 1).
      const Eigen::Quaterniond at = k < n - 1
                                        ? CumulativeRotation(&r_[k], 0.0, nullptr, nullptr)
                                        : CumulativeRotation(&r_[k - 1], 1.0, nullptr, nullptr);
      step[k] = LogQ(Eigen::Quaterniond(at.conjugate() * Q[k]));
      worst = std::max(worst, step[k].norm());
    }
    if (!(worst >= 1e-12)) break;
    for (int k = 0; k < n; ++k) r_[k + 1] = (r_[k + 1] * ExpQ(Eigen::Vector3d(1.5 * step[k])));
    for (int k = 0; k < n; ++k) r_[k + 1].normalize();
    extend_ends();
  }

  bias_t_.reserve(states.size());
  bias_.reserve(states.size());
  for (const NavState& s : states) {
    bias_t_.push_back(s.t_ns);
    Eigen::Matrix<double, 6, 1> b;
    b << s.bg, s.ba;
    bias_.push_back(b);
  }
}

BodyKinematics SplineMotion::At(TimeNs t_ns) const {
  const TimeNs t = std::clamp(t_ns, start_ns_, end_ns_);
  const double x = NsToSeconds(t - start_ns_) / h_;
  const int segments = static_cast<int>(c_.size()) - 3;
  const int k = std::clamp(static_cast<int>(std::floor(x)), 0, segments - 1);
  const double u = std::clamp(x - k, 0.0, 1.0);
  double b[4], db[4], ddb[4];
  Basis(u, b, db, ddb);
  BodyKinematics kin;
  kin.t_s = NsToSeconds(t_ns - start_ns_);
  kin.p_w_b.setZero();
  kin.v_w.setZero();
  kin.a_w.setZero();
  for (int j = 0; j < 4; ++j) {
    kin.p_w_b += b[j] * c_[k + j];
    kin.v_w += db[j] / h_ * c_[k + j];
    kin.a_w += ddb[j] / (h_ * h_) * c_[k + j];
  }
  Eigen::Vector3d w, a;
  kin.q_w_b = CumulativeRotation(&r_[k], u, &w, &a);
  kin.omega_b = w / h_;
  kin.alpha_b = a / (h_ * h_);
  kin.speed_m_s = kin.v_w.norm();
  return kin;
}

NavState SplineMotion::StateAt(TimeNs t_ns) const {
  const BodyKinematics kin = At(t_ns);
  NavState s;
  s.t_ns = t_ns;
  s.p_w_b = kin.p_w_b;
  s.q_w_b = kin.q_w_b;
  s.v_w = kin.v_w;
  const auto it = std::lower_bound(bias_t_.begin(), bias_t_.end(), t_ns);
  Eigen::Matrix<double, 6, 1> bias;
  if (it == bias_t_.begin()) {
    bias = bias_.front();
  } else if (it == bias_t_.end()) {
    bias = bias_.back();
  } else {
    const size_t j = static_cast<size_t>(it - bias_t_.begin());
    const double f = static_cast<double>(t_ns - bias_t_[j - 1]) /
                     static_cast<double>(bias_t_[j] - bias_t_[j - 1]);
    bias = (1.0 - f) * bias_[j - 1] + f * bias_[j];
  }
  s.bg = bias.head<3>();
  s.ba = bias.tail<3>();
  return s;
}

}  // namespace skerry::sim
