#include "skerry/twin/gnss_track.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace skerry {
namespace {

// The search box of gnss_track.h.
constexpr double kMinQ = 1e-4, kMaxQ = 1e3;         // m^2/s^3
constexpr double kMinSigma = 1e-3, kMaxSigma = 30;  // m
constexpr double kGridPerDecade = 8.0;
constexpr double kGoldenTolLog10 = 1e-7;
// Step in log sigma of the profile's second difference: the likelihood is about quadratic over
// it (relative sd of sigma ~ 1/sqrt(2 n), 1 % for a few thousand fixes) and its differences
// (~ n h^2) stay far above the rounding of sums of n terms.
constexpr double kProfileStep = 0.02;
constexpr double kLog2Pi = 1.8378770664093453;

// The innovation sums of one filter run: n innovations e_k of variance S_k (fixes 3 onwards).
struct InnovationSums {
  double n = 0.0;
  double sum_log_s = 0.0;      // sum log S_k
  double sum_e2_over_s = 0.0;  // sum e_k^2 / S_k

  InnovationSums& operator+=(const InnovationSums& o) {
    n += o.n;
    sum_log_s += o.sum_log_s;
    sum_e2_over_s += o.sum_e2_over_s;
    return *this;
  }
};

// What the smoother needs of a filter run, per fix k: the filtered mean and covariance (k >= 1)
// and the predicted ones (k >= 2).
struct FilterPass {
  std::vector<Eigen::Vector2d> x_f, x_p;
  std::vector<Eigen::Matrix2d> P_f, P_p;
};

// The Kalman filter of the white-noise-acceleration model (gnss_track.h) over the positions z at
// steps dt (dt[k] = t_{k+1} - t_k), started exactly at the second fix. Scalar arithmetic: this
// runs a thousand times per track.
InnovationSums RunFilter(const std::vector<double>& dt,
                         const std::vector<double>& z,
                         double q,
                         double sigma2,
                         FilterPass* pass = nullptr) {
  const size_t n = z.size();
  // The state at fix 1 from fixes 0 and 1 under a flat prior: p = z1, v = (z1 - z0) / dt with
  // the covariance H^-1 R H^-T of z0 = p - dt v + (n0 - w_p + dt w_v), z1 = p + n1, where
  // var(-w_p + dt w_v) = q dt^3 / 3.
  double d = dt[0];
  double p = z[1], v = (z[1] - z[0]) / d;
  double P00 = sigma2, P01 = sigma2 / d, P11 = (2.0 * sigma2 + q * d * d * d / 3.0) / (d * d);
  if (pass) {
    pass->x_f.assign(n, Eigen::Vector2d::Zero());
    pass->x_p.assign(n, Eigen::Vector2d::Zero());
    pass->P_f.assign(n, Eigen::Matrix2d::Zero());
    pass->P_p.assign(n, Eigen::Matrix2d::Zero());
    pass->x_f[1] << p, v;
    pass->P_f[1] << P00, P01, P01, P11;
  }
  InnovationSums sums;
  for (size_t k = 2; k < n; ++k) {
    d = dt[k - 1];
    // Predict: F x, F P F^T + Q.
    const double pp = p + d * v, vp = v;
    const double Pp00 = P00 + 2.0 * d * P01 + d * d * P11 + q * d * d * d / 3.0;
    const double Pp01 = P01 + d * P11 + q * d * d / 2.0;
    const double Pp11 = P11 + q * d;
    const double e = z[k] - pp;
    const double S = Pp00 + sigma2;
    sums.n += 1.0;
    sums.sum_log_s += std::log(S);
    sums.sum_e2_over_s += e * e / S;
    // Update, in the forms that do not subtract nearly equal numbers when sigma^2 << Pp00:
    // P00 - Pp00^2 / S = Pp00 sigma^2 / S, likewise P01; P11 kept positive semi-definite.
    p = pp + Pp00 / S * e;
    v = vp + Pp01 / S * e;
    P00 = Pp00 * sigma2 / S;
    P01 = Pp01 * sigma2 / S;
    P11 = std::max(Pp11 - Pp01 * Pp01 / S, P01 * P01 / P00);
    if (pass) {
      pass->x_p[k] << pp, vp;
      pass->P_p[k] << Pp00, Pp01, Pp01, Pp11;
      pass->x_f[k] << p, v;
      pass->P_f[k] << P00, P01, P01, P11;
    }
  }
  return sums;
}

// The log-likelihood of the innovations of a run with unit sigma and q = r, at sigma^2: every
// innovation variance scales with sigma^2 (Harvey 1989, sec. 3.4).
double LogLikelihood(const InnovationSums& unit, double sigma2) {
  return -0.5 *
         (unit.n * (kLog2Pi + std::log(sigma2)) + unit.sum_log_s + unit.sum_e2_over_s / sigma2);
}

// The maximum of f on [lo, hi] (log10 units): the best of a grid of kGridPerDecade points a
// decade, then golden section between its neighbours. Returns the argument; *f_max the value.
template <class F>
double MaximizeLog10(const F& f, double lo, double hi, double* f_max) {
  const int m = std::max(2, static_cast<int>(std::ceil((hi - lo) * kGridPerDecade)) + 1);
  const double step = (hi - lo) / (m - 1);
  int best = 0;
  double f_best = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < m; ++i) {
    const double fi = f(lo + i * step);
    if (fi > f_best) f_best = fi, best = i;
  }
  double a = lo + std::max(0, best - 1) * step, b = lo + std::min(m - 1, best + 1) * step;
  double x_best = lo + best * step;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = f(c), fd = f(d);
  while (b - a > kGoldenTolLog10) {
    if (fc >= fd) {
      b = d, d = c, fd = fc;
      c = b - g * (b - a), fc = f(c);
    } else {
      a = c, c = d, fc = fd;
      d = a + g * (b - a), fd = f(d);
    }
  }
  if (fc > f_best) f_best = fc, x_best = c;
  if (fd > f_best) f_best = fd, x_best = d;
  *f_max = f_best;
  return x_best;
}

// The ML fit of one group of axes (east and north pooled, or up) sharing q and sigma.
struct AxesFit {
  double q = 0.0, sigma = 0.0, log_likelihood = 0.0;
  IdentifiedValue sigma_value;
};

InnovationSums RunAxes(const std::vector<double>& dt,
                       const std::vector<std::vector<double>>& axes,
                       double r) {
  InnovationSums sum;
  for (const auto& z : axes) sum += RunFilter(dt, z, r, 1.0);
  return sum;
}

AxesFit FitAxes(const std::vector<double>& dt, const std::vector<std::vector<double>>& axes) {
  // Over log10 r, r = q / sigma^2, with sigma^2 at its closed-form maximum sum(e^2/S) / n
  // clamped into the box (the likelihood is unimodal in sigma^2 at a given r).
  auto sigma2_at = [&](const InnovationSums& unit, double r) {
    const double lo = std::max(kMinSigma * kMinSigma, kMinQ / r);
    const double hi = std::min(kMaxSigma * kMaxSigma, kMaxQ / r);
    return std::clamp(unit.sum_e2_over_s / unit.n, lo, std::max(lo, hi));
  };
  auto concentrated = [&](double log10_r) {
    const double r = std::pow(10.0, log10_r);
    const InnovationSums unit = RunAxes(dt, axes, r);
    return LogLikelihood(unit, sigma2_at(unit, r));
  };
  AxesFit fit;
  const double log10_r =
      MaximizeLog10(concentrated, std::log10(kMinQ / (kMaxSigma * kMaxSigma)),
                    std::log10(kMaxQ / (kMinSigma * kMinSigma)), &fit.log_likelihood);
  const double r = std::pow(10.0, log10_r);
  fit.sigma = std::sqrt(sigma2_at(RunAxes(dt, axes, r), r));
  fit.q = r * fit.sigma * fit.sigma;

  // The profile log-likelihood in log sigma: q maximised over the box at each sigma.
  auto profile = [&](double sigma) {
    double l = 0.0;
    MaximizeLog10(
        [&](double log10_q) {
          const double s2 = sigma * sigma;
          return LogLikelihood(RunAxes(dt, axes, std::pow(10.0, log10_q) / s2), s2);
        },
        std::log10(kMinQ), std::log10(kMaxQ), &l);
    return l;
  };
  fit.sigma_value.value = fit.sigma;
  const double s_lo = fit.sigma * std::exp(-kProfileStep);
  const double s_hi = fit.sigma * std::exp(kProfileStep);
  if (s_lo >= kMinSigma && s_hi <= kMaxSigma) {
    const double curvature =
        (profile(s_hi) - 2.0 * profile(fit.sigma) + profile(s_lo)) / (kProfileStep * kProfileStep);
    const double sd = fit.sigma / std::sqrt(-curvature);
    if (curvature < 0.0 && std::isfinite(sd)) {
      fit.sigma_value.sigma = sd;
      fit.sigma_value.identified = true;
    }
  }
  return fit;
}

// Rauch-Tung-Striebel (1965): smoothed [p, v] at every fix from the filter at (q, sigma).
std::vector<Eigen::Vector2d> Smooth(const std::vector<double>& dt,
                                    const std::vector<double>& z,
                                    double q,
                                    double sigma2) {
  const size_t n = z.size();
  FilterPass f;
  RunFilter(dt, z, q, sigma2, &f);
  std::vector<Eigen::Vector2d> x_s(n);
  x_s[n - 1] = f.x_f[n - 1];
  for (size_t k = n - 1; k-- > 1;) {
    Eigen::Matrix2d F;
    F << 1.0, dt[k], 0.0, 1.0;
    // C = P_f F^T P_p^-1, as C^T = P_p^-1 F P_f (P_p symmetric positive definite).
    const Eigen::Matrix2d C = f.P_p[k + 1].llt().solve(F * f.P_f[k]).transpose();
    x_s[k] = f.x_f[k] + C * (x_s[k + 1] - f.x_p[k + 1]);
  }
  // Fix 0: p(x0 | all) = int p(x0 | x1, z0) p(x1 | all) dx1, with, under a flat prior on x0,
  // x0 | x1 ~ N(F^-1 x1, F^-1 Q F^-T) conditioned on z0 = p0 + n0.
  const double d = dt[0];
  Eigen::Matrix2d F_inv, Q;
  F_inv << 1.0, -d, 0.0, 1.0;
  Q << d * d * d / 3.0, d * d / 2.0, d * d / 2.0, d;
  const Eigen::Matrix2d Q_back = q * F_inv * Q * F_inv.transpose();
  const Eigen::Vector2d m = F_inv * x_s[1];
  x_s[0] = m + Q_back.col(0) / (Q_back(0, 0) + sigma2) * (z[0] - m[0]);
  return x_s;
}

}  // namespace

GnssTrack SmoothGnssTrack(const std::vector<GnssFix>& fixes, const GnssTrackOptions& options) {
  const size_t n = fixes.size();
  if (n < 10) {
    throw std::invalid_argument("SmoothGnssTrack: needs at least 10 fixes, got " +
                                std::to_string(n));
  }
  if (!(options.min_speed_for_course_m_s >= 0.0 &&
        std::isfinite(options.min_speed_for_course_m_s))) {
    throw std::invalid_argument("SmoothGnssTrack: min_speed_for_course_m_s must be >= 0");
  }
  std::vector<double> dt(n - 1);
  // Positions relative to the first fix, per axis east, north, up.
  std::vector<std::vector<double>> z(3, std::vector<double>(n));
  const Eigen::Vector3d origin = fixes[0].p_w;
  for (size_t k = 0; k < n; ++k) {
    if (!fixes[k].p_w.allFinite()) {
      throw std::invalid_argument("SmoothGnssTrack: fix " + std::to_string(k) +
                                  " has a non-finite position");
    }
    if (k > 0) {
      if (fixes[k].t_ns <= fixes[k - 1].t_ns) {
        throw std::invalid_argument("SmoothGnssTrack: fix " + std::to_string(k) +
                                    " is not after the one before");
      }
      dt[k - 1] = NsToSeconds(fixes[k].t_ns - fixes[k - 1].t_ns);
    }
    for (int a = 0; a < 3; ++a) z[a][k] = fixes[k].p_w[a] - origin[a];
  }

  const AxesFit horizontal = FitAxes(dt, {z[0], z[1]});
  const AxesFit vertical = FitAxes(dt, {z[2]});
  GnssTrack out;
  out.accel_psd_horizontal = horizontal.q;
  out.accel_psd_vertical = vertical.q;
  out.white_sigma_horizontal_m = horizontal.sigma_value;
  out.white_sigma_vertical_m = vertical.sigma_value;
  out.log_likelihood = horizontal.log_likelihood + vertical.log_likelihood;

  std::vector<Eigen::Vector2d> x_s[3];
  for (int a = 0; a < 3; ++a) {
    const AxesFit& fit = a < 2 ? horizontal : vertical;
    x_s[a] = Smooth(dt, z[a], fit.q, fit.sigma * fit.sigma);
  }
  out.states.resize(n);
  for (size_t k = 0; k < n; ++k) {
    NavState& s = out.states[k];
    s.t_ns = fixes[k].t_ns;
    for (int a = 0; a < 3; ++a) {
      s.p_w_b[a] = origin[a] + x_s[a][k][0];
      s.v_w[a] = x_s[a][k][1];
    }
  }

  // Yaw along the course over ground where moving, held where not.
  std::vector<double> yaw(n, 0.0);
  std::vector<bool> moving(n, false);
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d& v = out.states[k].v_w;
    moving[k] = std::hypot(v.x(), v.y()) >= options.min_speed_for_course_m_s;
    if (moving[k]) yaw[k] = std::atan2(v.y(), v.x());
  }
  const auto first_moving = std::find(moving.begin(), moving.end(), true);
  double held = first_moving == moving.end() ? 0.0 : yaw[first_moving - moving.begin()];
  for (size_t k = 0; k < n; ++k) {
    if (moving[k]) held = yaw[k];
    out.states[k].q_w_b = Eigen::Quaterniond(Eigen::AngleAxisd(held, Eigen::Vector3d::UnitZ()));
  }
  return out;
}

}  // namespace skerry
