#include "skerry/twin/solve_pattern.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "median.h"

namespace skerry {
using twin_internal::Median;

namespace {

// floor(a / b) for b > 0 (C++ division truncates towards zero).
std::int64_t FloorDiv(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

struct Jump {
  double ratio = 0.0, z = 0.0;
};

// Mean square first difference across a solution time (phase + k period) against within one
// period, over the pairs `pairs` (index of the later fix), and the z-score of their difference.
Jump JumpAt(const std::vector<TimeNs>& t,
            const std::vector<Eigen::Vector2d>& e,
            const std::vector<size_t>& pairs,
            TimeNs period_ns,
            TimeNs phase_ns) {
  double s_a = 0.0, ss_a = 0.0, s_w = 0.0, ss_w = 0.0;
  int n_a = 0, n_w = 0;
  for (size_t i : pairs) {
    const double d2 = (e[i] - e[i - 1]).squaredNorm();
    if (FloorDiv(t[i] - phase_ns, period_ns) != FloorDiv(t[i - 1] - phase_ns, period_ns)) {
      s_a += d2;
      ss_a += d2 * d2;
      ++n_a;
    } else {
      s_w += d2;
      ss_w += d2 * d2;
      ++n_w;
    }
  }
  Jump j;
  if (n_a < 10 || n_w < 10 || s_w <= 0.0) return j;
  const double m_a = s_a / n_a, m_w = s_w / n_w;
  const double v_a = std::max(ss_a / n_a - m_a * m_a, 0.0) / n_a;
  const double v_w = std::max(ss_w / n_w - m_w * m_w, 0.0) / n_w;
  j.ratio = m_a / m_w;
  j.z = (m_a - m_w) / std::sqrt(std::max(v_a + v_w, 1e-300));
  return j;
}

}  // namespace

double ResidualCorrelationAtLag(const std::vector<TimeNs>& t_ns,
                                const std::vector<Eigen::Vector2d>& e_m,
                                double lag_s) {
  const size_t n = t_ns.size();
  if (n < 3 || e_m.size() != n) return 0.0;
  std::vector<double> east(n), north(n), dt(n - 1);
  for (size_t i = 0; i < n; ++i) {
    east[i] = e_m[i].x();
    north[i] = e_m[i].y();
    if (i + 1 < n) dt[i] = static_cast<double>(t_ns[i + 1] - t_ns[i]);
  }
  const Eigen::Vector2d med(Median(east), Median(north));
  const double tolerance_ns = 0.5 * Median(dt);
  const TimeNs lag_ns = SecondsToNs(lag_s);
  double c0 = 0.0, c = 0.0;
  size_t j = 0;
  for (size_t i = 0; i < n; ++i) {
    c0 += (e_m[i] - med).squaredNorm();
    // Two pointers: j the fix nearest to t_i + lag.
    const TimeNs target = t_ns[i] + lag_ns;
    while (j + 1 < n && std::llabs(t_ns[j + 1] - target) <= std::llabs(t_ns[j] - target)) ++j;
    if (j > i && static_cast<double>(std::llabs(t_ns[j] - target)) <= tolerance_ns) {
      c += (e_m[i] - med).dot(e_m[j] - med);
    }
  }
  return c0 > 0.0 ? c / c0 : 0.0;
}

SolvePattern IdentifySolvePattern(const std::vector<TimeNs>& t_all,
                                  const std::vector<Eigen::Vector2d>& e_all,
                                  const std::vector<bool>& gross,
                                  const SolvePatternOptions& o) {
  if (e_all.size() != t_all.size() || (!gross.empty() && gross.size() != t_all.size())) {
    throw std::invalid_argument("IdentifySolvePattern: one residual and gross flag per stamp");
  }
  std::vector<TimeNs> t;
  std::vector<Eigen::Vector2d> e;
  for (size_t i = 0; i < t_all.size(); ++i) {
    if (!gross.empty() && gross[i]) continue;
    t.push_back(t_all[i]);
    e.push_back(e_all[i]);
  }
  SolvePattern out;
  const size_t n = t.size();
  if (n < 30) return out;
  std::vector<double> dt(n - 1);
  for (size_t i = 0; i + 1 < n; ++i) dt[i] = NsToSeconds(t[i + 1] - t[i]);
  const double median_dt = Median(dt);

  // --- Each candidate period's best phase by the jump of the first differences. --------------
  // Kept: of the candidates that pass every test, the largest ratio (a multiple of the true
  // period counts some jumps as within, a fraction of it some differences without a jump as
  // across; both dilute it); none passing, the largest ratio, as not detected. The periodicity
  // test also keeps a fraction of the period out where another pattern locked to the second
  // (a stamp-phase timing error: docs/twin.md) jumps too.
  bool found = false;
  for (double period : o.candidate_periods_s) {
    if (!(median_dt > 0.0) || median_dt > period / 3.0) continue;  // too few fixes per period
    const TimeNs period_ns = SecondsToNs(period);
    // Consecutive fixes without a gap between them, less than half a period apart.
    std::vector<size_t> pairs;
    for (size_t i = 1; i < n; ++i) {
      if (dt[i - 1] <= std::min(1.5 * median_dt, 0.5 * period)) pairs.push_back(i);
    }
    const int steps = std::max(1, static_cast<int>(std::round(period / o.phase_step_s)));
    std::vector<Jump> jumps(static_cast<size_t>(steps));
    int arg = 0;
    for (int s = 0; s < steps; ++s) {
      jumps[static_cast<size_t>(s)] = JumpAt(t, e, pairs, period_ns, period_ns * s / steps);
      if (jumps[static_cast<size_t>(s)].ratio > jumps[static_cast<size_t>(arg)].ratio) arg = s;
    }
    SolvePattern c;
    c.period_s = period;
    c.jump_ratio = jumps[static_cast<size_t>(arg)].ratio;
    c.jump_z = jumps[static_cast<size_t>(arg)].z;
    // Every phase between the last fix before the solution and the first after it splits the
    // pairs alike: the middle of the run of phases (circular) as good as the best.
    const double level = 0.97 * c.jump_ratio;
    auto good = [&](int s) {
      return jumps[static_cast<size_t>((s % steps + steps) % steps)].ratio >= level;
    };
    int lo = arg, hi = arg;
    while (hi - lo + 1 < steps && good(lo - 1)) --lo;
    while (hi - lo + 1 < steps && good(hi + 1)) ++hi;
    c.phase_s = std::fmod(0.5 * (lo + hi) / steps * period + period, period);
    c.period_correlation = ResidualCorrelationAtLag(t, e, period);
    c.half_period_correlation = ResidualCorrelationAtLag(t, e, 0.5 * period);
    c.detected = c.jump_ratio >= o.min_jump_ratio && c.jump_z >= o.min_jump_z &&
                 c.period_correlation - c.half_period_correlation >= o.min_periodicity;
    const bool better = (c.detected && !out.detected) ||
                        (c.detected == out.detected && c.jump_ratio > out.jump_ratio);
    if (!found || better) out = c;
    found = true;
  }
  if (!out.detected) return out;

  // --- A line a + b s per period and axis, s = t - t_solution. -------------------------------
  const TimeNs period_ns = SecondsToNs(out.period_s);
  const TimeNs phase_ns = SecondsToNs(out.phase_s);
  std::map<std::int64_t, std::vector<size_t>> periods;
  for (size_t i = 0; i < n; ++i) periods[FloorDiv(t[i] - phase_ns, period_ns)].push_back(i);
  struct Line {
    std::int64_t k;
    Eigen::Vector2d a, b;
    double n, s_mean, sxx;
  };
  std::vector<Line> lines;
  double rss = 0.0, dof = 0.0;
  for (const auto& [k, idx] : periods) {
    if (idx.size() < 3) continue;
    Line l{
        k,  Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), static_cast<double>(idx.size()), 0.0,
        0.0};
    std::vector<double> s(idx.size());
    Eigen::Vector2d e_mean = Eigen::Vector2d::Zero();
    for (size_t j = 0; j < idx.size(); ++j) {
      s[j] = NsToSeconds(t[idx[j]] - phase_ns - k * period_ns);
      l.s_mean += s[j] / l.n;
      e_mean += e[idx[j]] / l.n;
    }
    Eigen::Vector2d sxy = Eigen::Vector2d::Zero();
    for (size_t j = 0; j < idx.size(); ++j) {
      l.sxx += (s[j] - l.s_mean) * (s[j] - l.s_mean);
      sxy += (s[j] - l.s_mean) * (e[idx[j]] - e_mean);
    }
    if (!(l.sxx > 0.0)) continue;
    l.b = sxy / l.sxx;
    l.a = e_mean - l.b * l.s_mean;
    for (size_t j = 0; j < idx.size(); ++j) {
      rss += (e[idx[j]] - l.a - l.b * s[j]).squaredNorm();
    }
    dof += 2.0 * (l.n - 2.0);
    lines.push_back(l);
  }
  out.periods = static_cast<int>(lines.size());
  if (lines.size() < 10 || dof <= 0.0) {
    out.detected = false;
    return out;
  }
  const double white2 = rss / dof;
  const double m = static_cast<double>(lines.size());
  Eigen::Vector2d a_mean = Eigen::Vector2d::Zero(), b_mean = Eigen::Vector2d::Zero();
  for (const Line& l : lines) {
    a_mean += l.a / m;
    b_mean += l.b / m;
  }
  double var_a = 0.0, var_b = 0.0, noise_a = 0.0, noise_b = 0.0, lag1 = 0.0;
  int pairs = 0;
  for (size_t j = 0; j < lines.size(); ++j) {
    const Line& l = lines[j];
    var_a += (l.a - a_mean).squaredNorm() / (2.0 * m);
    var_b += (l.b - b_mean).squaredNorm() / (2.0 * m);
    // The white noise's share in a line's value at s = 0 and in its slope.
    noise_a += white2 * (1.0 / l.n + l.s_mean * l.s_mean / l.sxx) / m;
    noise_b += white2 / l.sxx / m;
    if (j + 1 < lines.size() && lines[j + 1].k == l.k + 1) {
      lag1 += (l.b - b_mean).dot(lines[j + 1].b - b_mean);
      pairs += 2;
    }
  }
  const double n_values = 2.0 * m;
  const double white = std::sqrt(white2);
  out.white_sigma_horizontal_m = {white, white / std::sqrt(2.0 * dof), true};
  const double sigma_a2 = var_a - noise_a, sigma_b2 = var_b - noise_b;
  // The sd of a variance estimate over N values, signal sigma^2 correlated with factor f plus
  // independent noise nu: sqrt(2 / N) sqrt(sigma^4 f + 2 sigma^2 nu + nu^2); of its square
  // root, that over 2 sigma.
  auto sd_of_sigma = [&](double sigma2, double nu, double f) {
    return std::sqrt(2.0 / n_values) *
           std::sqrt(sigma2 * sigma2 * f + 2.0 * sigma2 * nu + nu * nu) / (2.0 * std::sqrt(sigma2));
  };
  if (sigma_a2 > 0.0) {
    out.offset_sigma_m = {std::sqrt(sigma_a2), sd_of_sigma(sigma_a2, noise_a, 1.0), true};
  }
  if (sigma_b2 > 0.0) {
    const double s = std::sqrt(sigma_b2);
    const double rho = pairs > 0 ? std::clamp(lag1 / pairs / sigma_b2, -0.99, 0.99) : 0.0;
    const double r2 = rho * rho;
    out.propagation_velocity_sigma_m_s = {
        s, sd_of_sigma(sigma_b2, noise_b, (1.0 + r2) / (1.0 - r2)), true};
    if (rho > 0.05 && pairs >= 20) {
      const double tau = -out.period_s / std::log(rho);
      const double sd_rho = std::sqrt((1.0 - r2) / pairs);
      const double dtau_drho = out.period_s / (rho * std::log(rho) * std::log(rho));
      out.propagation_velocity_tau_s = {tau, dtau_drho * sd_rho, true};
    }
  }
  return out;
}

}  // namespace skerry
