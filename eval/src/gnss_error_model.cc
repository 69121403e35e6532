#include "skerry/eval/gnss_error_model.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace skerry {
namespace {

constexpr int kMinFixes = 30;
constexpr double kMadToSigma = 1.4826;       // MAD -> sigma of a Gaussian
constexpr double kStretchGapPeriods = 10.0;  // a longer interval ends a stretch
constexpr int kMedianWindow = 11;            // fixes in the running median of (b)
constexpr double kLatencyRobustSigmas = 5.0;
constexpr double kLatencyMinSpreadMS = 0.5;  // RMS horizontal velocity about its mean
constexpr double kDriftMinShareOfWhite = 0.1;
constexpr double kAutoMaxLagPeriods = 300.0;
constexpr int kTauGridPoints = 241;
constexpr double kGlsLagRatio = 1.15;  // the weighted fit's lags: 1, 2, ... growing by this ratio
constexpr int kGlsIterations = 3;
constexpr double kGlsRidge = 1e-3;  // of the largest variance, added to the diagonal

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + m, v.end());
  const double hi = v[m];
  if (v.size() % 2 == 1) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + m));
}

// 1.4826 MAD: the standard deviation of a Gaussian, robust to a minority of gross errors.
double RobustSigma(std::vector<double> v) {
  const double med = Median(v);
  for (double& x : v) x = std::abs(x - med);
  return kMadToSigma * Median(std::move(v));
}

// Var(mean of x over [0, S]) / sigma^2 for a Gauss-Markov x of correlation time T, x = S / T:
// (1/S^2) int int exp(-|u - w| / T) du dw = 2 (x - 1 + exp(-x)) / x^2.
double MeanVarianceShare(double x) {
  if (x < 1e-4) return 1.0 - x / 3.0;
  return 2.0 * (x - 1.0 + std::exp(-x)) / (x * x);
}

// The stretches of `t`: [begin, end) index ranges without an interval above `max_gap_s`.
std::vector<std::pair<std::size_t, std::size_t>> Stretches(const std::vector<double>& t,
                                                           double max_gap_s) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  std::size_t begin = 0;
  for (std::size_t i = 1; i <= t.size(); ++i) {
    if (i == t.size() || t[i] - t[i - 1] > max_gap_s) {
      out.emplace_back(begin, i);
      begin = i;
    }
  }
  return out;
}

// One pass of (a)-(c) on a series (the data or a bootstrap replica).
struct ChainResult {
  double latency = 0.0;  // least-squares estimate, before any identification
  double latency_formal_sigma = 0.0;
  double velocity_spread = 0.0;  // RMS horizontal velocity about its mean, m/s
  int outliers = 0;
  double outlier_share = 0.0;
  double outlier_sigma = 0.0;  // 0 without outliers
  // Index 0 horizontal (per axis), 1 vertical.
  double white[2] = {0.0, 0.0};  // with the drift model
  double drift[2] = {0.0, 0.0};
  double total[2] = {0.0, 0.0};  // sqrt(C(0)): the white sigma of a model without drift
  double tau = 0.0;
  bool tau_resolved = false;
};

struct ChainSetup {
  double period = 0.0;
  int lags = 0;  // K
  double threshold = 5.0;
  bool remove_latency = true;
};

// (a) Latency by least squares with an intercept per horizontal axis, refitted once without the
// fixes beyond kLatencyRobustSigmas robust sigmas.
void FitLatency(const GnssResidualSeries& s, ChainResult* out) {
  const std::size_t n = s.t_s.size();
  std::vector<char> use(n, 1);
  double latency = 0.0;
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Vector2d mean_e = Eigen::Vector2d::Zero(), mean_v = Eigen::Vector2d::Zero();
    std::size_t m = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!use[i]) continue;
      mean_e += s.e_enu_m[i].head<2>();
      mean_v += s.v_enu_m_s[i].head<2>();
      ++m;
    }
    mean_e /= static_cast<double>(m);
    mean_v /= static_cast<double>(m);
    double svv = 0.0, sve = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!use[i]) continue;
      const Eigen::Vector2d dv = s.v_enu_m_s[i].head<2>() - mean_v;
      svv += dv.squaredNorm();
      sve += dv.dot(s.e_enu_m[i].head<2>() - mean_e);
    }
    latency = svv > 0.0 ? -sve / svv : 0.0;
    std::vector<double> r;
    r.reserve(2 * n);
    double ss = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d ri =
          s.e_enu_m[i].head<2>() - mean_e + (s.v_enu_m_s[i].head<2>() - mean_v) * latency;
      if (use[i]) ss += ri.squaredNorm();
      r.push_back(ri.x());
      r.push_back(ri.y());
    }
    out->velocity_spread = std::sqrt(svv / static_cast<double>(m));
    out->latency_formal_sigma = svv > 0.0 && m > 2 ? std::sqrt(ss / (2.0 * m - 3.0) / svv)
                                                   : std::numeric_limits<double>::infinity();
    if (pass == 1) break;
    const double limit = kLatencyRobustSigmas * RobustSigma(r);
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i) {
      use[i] = std::abs(r[2 * i]) <= limit && std::abs(r[2 * i + 1]) <= limit;
      kept += use[i];
    }
    if (kept < n / 2) std::fill(use.begin(), use.end(), 1);  // no majority: keep the first fit
  }
  out->latency = latency;
}

// One autocovariance curve: east and north pooled, or up.
struct Curve {
  std::vector<double> c;      // C(k), k = 0..K
  std::vector<double> w;      // pair counts
  std::vector<double> gamma;  // the variogram: half the mean squared difference at lag k
};

// The pilot's error: pair-count-weighted squared error over k >= 1 of the model sd^2 (g_k - b),
// g_k = exp(-k dt / T), with its best sd^2 >= 0 in *sd2.
double CurveError(const Curve& curve, const std::vector<double>& g, double b, double* sd2) {
  double a = 0.0, bc = 0.0, cc = 0.0;
  for (std::size_t k = 1; k < curve.c.size(); ++k) {
    const double x = g[k] - b;
    a += curve.w[k] * x * x;
    bc += curve.w[k] * x * curve.c[k];
    cc += curve.w[k] * curve.c[k] * curve.c[k];
  }
  const double s = a > 0.0 ? std::max(0.0, bc / a) : 0.0;
  *sd2 = s;
  return cc - 2.0 * s * bc + s * s * a;
}

// sum_m C(m) C(m + d) for C(m) = sd2 rho^|m| + sw2 [m = 0], d >= 0, rho_d = rho^d; with
// sum_m rho^(|m| + |m + d|) = rho^d (d + (1 + rho^2) / (1 - rho^2)).
double LaggedProductSum(int d, double rho, double rho_d, double sw2, double sd2) {
  return sd2 * sd2 * rho_d * (d + (1.0 + rho * rho) / (1.0 - rho * rho)) + 2.0 * sd2 * sw2 * rho_d +
         (d == 0 ? sw2 * sw2 : 0.0);
}

// One curve's sample autocovariances at `lags`, whitened by the Cholesky factor of their
// covariance under a pilot model (sw2, sd2, rho = exp(-dt / T)). For a Gaussian series sampled
// evenly n times, Bartlett's approximation (Priestley 1981, eq. 5.3.21):
//   cov(C(k), C(l)) = (1/n) S(k, l),   S(k, l) = sum_m [C(m) C(m + l - k) + C(m + l) C(m - k)].
// Its 1/n assumes every lag has its n pairs. With gaps the lags' pair counts n_k differ, by
// orders of magnitude in a bootstrap replica whose short blocks reach the lags beyond their own
// length only where one straddles a gap. Bartlett's derivation, C(k) = (1/n_k) sum over its pairs
// (i, i + k) of y_i y_(i+k), each first fix summing S(k, l) over the other lag's pairs, gives
//   cov(C(k), C(l)) = (|P_k and P_l| / (n_k n_l)) S(k, l) = S(k, l) / max(n_k, n_l)
// where one lag's first fixes P are a subset of the other's (most fixes of a run pair at both
// lags); Bartlett's 1/n with even sampling, and positive semi-definite (the Schur product of S
// with the kernel min(1/n_k, 1/n_l)). Without it a handful of pairs across a gap weighs as much
// as a whole lag, and the fit bends T to their noise.
struct WhitenedCurve {
  Eigen::LLT<Eigen::MatrixXd> llt;
  Eigen::VectorXd z;  // L^-1 C(lags)
  bool ok = false;
};

WhitenedCurve Whiten(
    const Curve& curve, const std::vector<int>& lags, double rho, double sw2, double sd2) {
  const int l = static_cast<int>(lags.size());
  std::vector<double> rho_d(2 * lags.back() + 1, 1.0);
  for (std::size_t d = 1; d < rho_d.size(); ++d) rho_d[d] = rho_d[d - 1] * rho;
  auto sum = [&](int d) { return LaggedProductSum(d, rho, rho_d[d], sw2, sd2); };
  Eigen::MatrixXd cov(l, l);
  for (int a = 0; a < l; ++a) {
    for (int b = 0; b < l; ++b) {
      cov(a, b) = sum(std::abs(lags[b] - lags[a])) + sum(lags[b] + lags[a]);
    }
  }
  // The lags' estimates are nearly collinear; a small ridge keeps the weights from resting on
  // the covariance's smallest, least certain directions.
  cov.diagonal().array() += kGlsRidge * cov.diagonal().maxCoeff();
  for (int a = 0; a < l; ++a) {
    for (int b = 0; b < l; ++b) cov(a, b) /= std::max(curve.w[lags[a]], curve.w[lags[b]]);
  }
  WhitenedCurve out;
  out.llt.compute(cov);
  if (out.llt.info() != Eigen::Success || !(cov.diagonal().maxCoeff() > 0.0)) return out;
  Eigen::VectorXd c(l);
  for (int a = 0; a < l; ++a) c(a) = curve.c[lags[a]];
  out.z = out.llt.matrixL().solve(c);
  out.ok = true;
  return out;
}

// The generalised least-squares error of the model sd^2 x, x = g(lags) - b, against a whitened
// curve, with its best sd^2 >= 0 in *sd2.
double WhitenedError(const WhitenedCurve& curve, const Eigen::VectorXd& x, double* sd2) {
  const Eigen::VectorXd xw = curve.llt.matrixL().solve(x);
  const double a = xw.squaredNorm(), bc = xw.dot(curve.z);
  const double s = a > 0.0 ? std::max(0.0, bc / a) : 0.0;
  *sd2 = s;
  return curve.z.squaredNorm() - 2.0 * s * bc + s * s * a;
}

// The minimum of f over [lo, hi]: a grid of kTauGridPoints in log x, then golden section between
// the best point's neighbours.
template <typename F>
double MinimiseOverLogGrid(const F& f, double lo, double hi) {
  const double log_lo = std::log(lo), log_hi = std::log(hi);
  const double step = (log_hi - log_lo) / (kTauGridPoints - 1);
  double best = std::numeric_limits<double>::infinity();
  int best_i = 0;
  for (int i = 0; i < kTauGridPoints; ++i) {
    const double fi = f(std::exp(log_lo + step * i));
    if (fi < best) {
      best = fi;
      best_i = i;
    }
  }
  double a = log_lo + step * std::max(best_i - 1, 0);
  double c = log_lo + step * std::min(best_i + 1, kTauGridPoints - 1);
  const double r = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = c - r * (c - a), x2 = a + r * (c - a);
  double f1 = f(std::exp(x1)), f2 = f(std::exp(x2));
  for (int it = 0; it < 30; ++it) {  // the bracket shrinks to 1e-6 of a grid step
    if (f1 < f2) {
      c = x2;
      x2 = x1;
      f2 = f1;
      x1 = c - r * (c - a);
      f1 = f(std::exp(x1));
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + r * (c - a);
      f2 = f(std::exp(x2));
    }
  }
  return std::exp(0.5 * (a + c));
}

ChainResult RunChain(const GnssResidualSeries& series, const ChainSetup& setup) {
  ChainResult out;
  const std::size_t n = series.t_s.size();
  const std::vector<double>& t = series.t_s;
  FitLatency(series, &out);
  const double latency = setup.remove_latency ? out.latency : 0.0;
  std::vector<Eigen::Vector3d> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = series.e_enu_m[i] + series.v_enu_m_s[i] * latency;

  // (b) Gross errors.
  const auto stretches = Stretches(t, kStretchGapPeriods * setup.period);
  double scale[3];
  for (int a = 0; a < 3; ++a) {
    std::vector<double> d;
    d.reserve(n);
    for (const auto& [begin, end] : stretches) {
      for (std::size_t i = begin + 1; i < end; ++i) d.push_back(x[i](a) - x[i - 1](a));
    }
    scale[a] = std::max(RobustSigma(std::move(d)) / std::sqrt(2.0), 1e-9);
  }
  std::vector<char> inlier(n, 1);
  double outlier_ss = 0.0;
  double window[kMedianWindow];
  for (const auto& [begin, end] : stretches) {
    const std::size_t w = std::min<std::size_t>(kMedianWindow, end - begin);
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t lo =
          std::min(std::max(i, begin + w / 2) - w / 2, end - w);  // clamped to the stretch
      double dev2 = 0.0, q2 = 0.0;
      for (int a = 0; a < 2; ++a) {
        for (std::size_t j = 0; j < w; ++j) window[j] = x[lo + j](a);
        std::nth_element(window, window + w / 2, window + w);
        double med = window[w / 2];
        if (w % 2 == 0) med = 0.5 * (med + *std::max_element(window, window + w / 2));
        const double dev = x[i](a) - med;
        dev2 += dev * dev;
        q2 += (dev / scale[a]) * (dev / scale[a]);
      }
      if (q2 > setup.threshold * setup.threshold) {
        inlier[i] = 0;
        ++out.outliers;
        outlier_ss += dev2;
      }
    }
  }
  out.outlier_share = static_cast<double>(out.outliers) / static_cast<double>(n);
  out.outlier_sigma = out.outliers > 0 ? std::sqrt(outlier_ss / out.outliers) : 0.0;

  // (c) Autocovariance of the inliers about their means.
  std::vector<std::size_t> idx;
  idx.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (inlier[i]) idx.push_back(i);
  }
  const std::size_t m = idx.size();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i : idx) mean += x[i];
  mean /= static_cast<double>(std::max<std::size_t>(m, 1));
  // Plain arrays: the double loop over pairs below is nearly all of the fit's time.
  std::vector<double> tt(m), ye(m), yn(m), yu(m);
  for (std::size_t j = 0; j < m; ++j) {
    tt[j] = t[idx[j]];
    ye[j] = x[idx[j]].x() - mean.x();
    yn[j] = x[idx[j]].y() - mean.y();
    yu[j] = x[idx[j]].z() - mean.z();
  }
  const int K = setup.lags;
  const double dt = setup.period;
  const double inv_dt = 1.0 / dt;
  const double reach = K + 0.5;  // in periods
  struct LagSums {
    double c_h = 0.0, c_v = 0.0, gamma_h = 0.0, gamma_v = 0.0, pairs = 0.0;
  };
  std::vector<LagSums> sums(K + 1);
  for (std::size_t i = 0; i < m; ++i) {
    sums[0].c_h += ye[i] * ye[i] + yn[i] * yn[i];
    sums[0].c_v += yu[i] * yu[i];
    sums[0].pairs += 1.0;
    for (std::size_t j = i + 1; j < m; ++j) {
      const double lag = (tt[j] - tt[i]) * inv_dt;
      if (lag >= reach) break;
      // Two distinct fixes within half a period (lag 0) share no white noise: skipped.
      const int k = static_cast<int>(lag + 0.5);
      if (k == 0) continue;
      const double de = ye[j] - ye[i], dn = yn[j] - yn[i], du = yu[j] - yu[i];
      LagSums& sk = sums[k];
      sk.c_h += ye[i] * ye[j] + yn[i] * yn[j];
      sk.c_v += yu[i] * yu[j];
      sk.gamma_h += 0.5 * (de * de + dn * dn);
      sk.gamma_v += 0.5 * du * du;
      sk.pairs += 1.0;
    }
  }
  Curve h, v;  // east and north pooled; up
  for (const LagSums& sk : sums) {
    const double n_h = std::max(2.0 * sk.pairs, 1.0), n_v = std::max(sk.pairs, 1.0);
    h.c.push_back(sk.c_h / n_h);
    h.gamma.push_back(sk.gamma_h / n_h);
    h.w.push_back(2.0 * sk.pairs);
    v.c.push_back(sk.c_v / n_v);
    v.gamma.push_back(sk.gamma_v / n_v);
    v.w.push_back(sk.pairs);
  }
  out.total[0] = std::sqrt(h.c[0]);
  out.total[1] = std::sqrt(v.c[0]);

  // The stretches of the inliers, for the mean-removal bias b(T).
  const auto inlier_stretches = Stretches(tt, kStretchGapPeriods * dt);
  auto bias = [&](double tau) {
    double b = 0.0;
    for (const auto& [begin, end] : inlier_stretches) {
      const double share = static_cast<double>(end - begin) / static_cast<double>(m);
      b += share * share * MeanVarianceShare((tt[end - 1] - tt[begin]) / tau);
    }
    return b;
  };
  std::vector<double> g(K + 1);
  auto objective = [&](double tau, double* sd2_h, double* sd2_v) {
    const double q = std::exp(-dt / tau);
    g[0] = 1.0;
    for (int k = 1; k <= K; ++k) g[k] = g[k - 1] * q;
    const double b = bias(tau);
    const double e_h = CurveError(h, g, b, sd2_h);
    const double e_v = CurveError(v, g, b, sd2_v);
    return e_h / std::max(h.c[0] * h.c[0], 1e-300) + e_v / std::max(v.c[0] * v.c[0], 1e-300);
  };
  if (K < 2 || m < 3) {
    out.white[0] = out.total[0];
    out.white[1] = out.total[1];
    return out;
  }
  // The pilot: each lag weighted by its pair count.
  double sd2_h = 0.0, sd2_v = 0.0;
  const double tau_lo = 0.5 * dt, tau_hi = 20.0 * K * dt;
  out.tau = MinimiseOverLogGrid([&](double tau) { return objective(tau, &sd2_h, &sd2_v); }, tau_lo,
                                tau_hi);
  objective(out.tau, &sd2_h, &sd2_v);
  // The shortest lag with pairs, for the white variance.
  int k1 = 1;
  while (k1 < K && h.w[k1] == 0.0) ++k1;
  auto white2 = [&](const Curve& curve, double sd2) {
    return std::max(0.0, curve.gamma[k1] - sd2 * (1.0 - std::exp(-k1 * dt / out.tau)));
  };
  // Then weighted by the inverse of the estimates' covariance under the previous fit, on lags
  // thinned geometrically (neighbouring lags carry nearly the same information), iterated.
  std::vector<int> lags;
  for (double x = 1.0; x <= K + 0.5; x = std::max(x * kGlsLagRatio, x + 1.0)) {
    const int k = static_cast<int>(std::lround(x));
    if (k <= K && (lags.empty() || k > lags.back()) && h.w[k] > 0.0) lags.push_back(k);
  }
  Eigen::VectorXd model(lags.size());
  for (int it = 0; it < kGlsIterations && lags.size() >= 2; ++it) {
    const double rho = std::exp(-dt / out.tau);
    const WhitenedCurve wh = Whiten(h, lags, rho, white2(h, sd2_h), sd2_h);
    const WhitenedCurve wv = Whiten(v, lags, rho, white2(v, sd2_v), sd2_v);
    if (!wh.ok || !wv.ok) break;
    auto weighted = [&](double tau) {
      const double b = bias(tau);
      for (std::size_t a = 0; a < lags.size(); ++a) model(a) = std::exp(-lags[a] * dt / tau) - b;
      return WhitenedError(wh, model, &sd2_h) + WhitenedError(wv, model, &sd2_v);
    };
    out.tau = MinimiseOverLogGrid(weighted, tau_lo, tau_hi);
    weighted(out.tau);
  }
  out.tau_resolved = out.tau >= 2.0 * dt && out.tau <= 10.0 * K * dt;
  out.drift[0] = std::sqrt(sd2_h);
  out.drift[1] = std::sqrt(sd2_v);
  // The white variance from the shortest lag's variogram, gamma(k) = sw^2 + sd^2 (1 - g_k), not
  // from C(0) - sd^2 (1 - b): the latter inherits the whole error of sd^2 (tens of percent of a
  // small sw^2), the former only that of the drift's small increment over one lag.
  out.white[0] = std::sqrt(white2(h, sd2_h));
  out.white[1] = std::sqrt(white2(v, sd2_v));
  return out;
}

// Sample standard deviation of the finite entries (0 for fewer than 2).
double StandardDeviation(const std::vector<double>& v) {
  double sum = 0.0, sum2 = 0.0;
  int count = 0;
  for (double x : v) {
    if (!std::isfinite(x)) continue;
    sum += x;
    ++count;
  }
  if (count < 2) return 0.0;
  const double mean = sum / count;
  for (double x : v) {
    if (std::isfinite(x)) sum2 += (x - mean) * (x - mean);
  }
  return std::sqrt(sum2 / (count - 1));
}

void Validate(const GnssResidualSeries& s, const GnssFitOptions& o) {
  const std::string where = "FitGnssErrorModel: ";
  const std::size_t n = s.t_s.size();
  if (s.e_enu_m.size() != n || s.v_enu_m_s.size() != n) {
    throw std::invalid_argument(where + "t_s, e_enu_m and v_enu_m_s differ in length (" +
                                std::to_string(n) + ", " + std::to_string(s.e_enu_m.size()) + ", " +
                                std::to_string(s.v_enu_m_s.size()) + ")");
  }
  if (n < static_cast<std::size_t>(kMinFixes)) {
    throw std::invalid_argument(where + std::to_string(n) + " fixes, at least " +
                                std::to_string(kMinFixes) + " needed");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::string at = "[" + std::to_string(i) + "]";
    if (!std::isfinite(s.t_s[i])) throw std::invalid_argument(where + "t_s" + at + " not finite");
    if (i > 0 && !(s.t_s[i] > s.t_s[i - 1])) {
      throw std::invalid_argument(where + "t_s" + at + " not after t_s[" + std::to_string(i - 1) +
                                  "]");
    }
    if (!s.e_enu_m[i].allFinite()) {
      throw std::invalid_argument(where + "e_enu_m" + at + " not finite");
    }
    if (!s.v_enu_m_s[i].allFinite()) {
      throw std::invalid_argument(where + "v_enu_m_s" + at + " not finite");
    }
  }
  if (!(o.outlier_threshold_sigma > 0.0) || !std::isfinite(o.outlier_threshold_sigma)) {
    throw std::invalid_argument(where + "outlier_threshold_sigma must be > 0");
  }
  if (o.bootstrap_replicas < 0) throw std::invalid_argument(where + "bootstrap_replicas < 0");
  if (!(o.max_lag_s >= 0.0) || !std::isfinite(o.max_lag_s)) {
    throw std::invalid_argument(where + "max_lag_s must be >= 0");
  }
}

}  // namespace

GnssErrorModelFit FitGnssErrorModel(const GnssResidualSeries& series,
                                    const GnssFitOptions& options) {
  Validate(series, options);
  const std::vector<double>& t = series.t_s;
  const std::size_t n = t.size();
  std::vector<double> intervals(n - 1);
  for (std::size_t i = 1; i < n; ++i) intervals[i - 1] = t[i] - t[i - 1];
  ChainSetup setup;
  setup.period = Median(intervals);
  const double span = t.back() - t.front();
  const double max_lag = options.max_lag_s > 0.0
                             ? options.max_lag_s
                             : std::min(0.1 * span, kAutoMaxLagPeriods * setup.period);
  setup.lags = static_cast<int>(std::floor(max_lag / setup.period + 1e-9));
  setup.threshold = options.outlier_threshold_sigma;
  setup.remove_latency = true;
  ChainResult main = RunChain(series, setup);

  // (d) Moving block bootstrap. Blocks of consecutive fixes, each placed after the previous one
  // with a gap longer than the largest lag and than a stretch break, so no pair, difference or
  // running median spans two blocks.
  const int replicas = options.bootstrap_replicas;
  const double block_s = std::max(10.0 * setup.period, 3.0 * main.tau);
  const std::size_t block =
      std::clamp<std::size_t>(static_cast<std::size_t>(std::lround(block_s / setup.period)), 1,
                              std::max<std::size_t>(n / 5, 1));
  const double separation = (setup.lags + kStretchGapPeriods + 2.0 * kMedianWindow) * setup.period;
  std::vector<double> latency(replicas), share(replicas), outlier_sigma, tau(replicas);
  std::vector<double> white[2], drift[2], total[2];
  for (int a = 0; a < 2; ++a) {
    white[a].resize(replicas);
    drift[a].resize(replicas);
    total[a].resize(replicas);
  }
  std::mt19937_64 rng(options.seed);
  GnssResidualSeries replica;
  replica.t_s.reserve(n);
  replica.e_enu_m.reserve(n);
  replica.v_enu_m_s.reserve(n);
  for (int r = 0; r < replicas; ++r) {
    replica.t_s.clear();
    replica.e_enu_m.clear();
    replica.v_enu_m_s.clear();
    double offset = 0.0;
    while (replica.t_s.size() < n) {
      // rng() % range: deterministic on every standard library (the distributions are not); the
      // modulo bias, about n / 2^64, is nil.
      const std::size_t start = static_cast<std::size_t>(rng() % (n - block + 1));
      const std::size_t take = std::min(block, n - replica.t_s.size());
      for (std::size_t j = start; j < start + take; ++j) {
        replica.t_s.push_back(offset + t[j] - t[start]);
        replica.e_enu_m.push_back(series.e_enu_m[j]);
        replica.v_enu_m_s.push_back(series.v_enu_m_s[j]);
      }
      offset = replica.t_s.back() + separation;
    }
    const ChainResult rr = RunChain(replica, setup);
    latency[r] = rr.latency;
    share[r] = rr.outlier_share;
    if (rr.outliers > 0) outlier_sigma.push_back(rr.outlier_sigma);
    tau[r] = rr.tau;
    for (int a = 0; a < 2; ++a) {
      white[a][r] = rr.white[a];
      drift[a][r] = rr.drift[a];
      total[a][r] = rr.total[a];
    }
  }

  GnssErrorModelFit fit;
  fit.samples = static_cast<int>(n);
  fit.period_s = setup.period;
  fit.latency_s.value = main.latency;
  fit.latency_s.sigma = replicas > 0 ? StandardDeviation(latency) : main.latency_formal_sigma;
  fit.latency_s.identified =
      main.velocity_spread > kLatencyMinSpreadMS ||
      (fit.latency_s.sigma > 0.0 && fit.latency_s.sigma < std::abs(main.latency));
  if (!fit.latency_s.identified) {
    // The model without latency: the rest refitted on the residuals as they are. Their sigmas
    // stay the bootstrap's, whose replicas removed a latency within its own noise.
    fit.latency_s.value = 0.0;
    setup.remove_latency = false;
    main = RunChain(series, setup);
  }
  fit.outliers = main.outliers;
  fit.outlier_share = {main.outlier_share, StandardDeviation(share), true};
  fit.outlier_sigma_horizontal_m = {main.outlier_sigma, StandardDeviation(outlier_sigma),
                                    main.outliers >= 2};
  IdentifiedValue* white_out[2] = {&fit.white_sigma_horizontal_m, &fit.white_sigma_vertical_m};
  IdentifiedValue* drift_out[2] = {&fit.drift_sigma_horizontal_m, &fit.drift_sigma_vertical_m};
  // T is resolved when it lies inside the grid's trusted range and, with a bootstrap, the
  // replicas agree on it to better than its own size (without a drift they scatter over the
  // whole grid).
  const double tau_sigma = StandardDeviation(tau);
  const bool tau_resolved = main.tau_resolved && (replicas == 0 || tau_sigma < main.tau);
  bool any_drift = false;
  for (int a = 0; a < 2; ++a) {
    const bool seen = tau_resolved && main.drift[a] > 0.0 &&
                      main.drift[a] >= kDriftMinShareOfWhite * main.white[a];
    any_drift |= seen;
    *drift_out[a] = {seen ? main.drift[a] : 0.0, StandardDeviation(drift[a]), seen};
    *white_out[a] = seen ? IdentifiedValue{main.white[a], StandardDeviation(white[a]), true}
                         : IdentifiedValue{main.total[a], StandardDeviation(total[a]), true};
  }
  fit.drift_tau_s = {main.tau, tau_sigma, any_drift};
  return fit;
}

}  // namespace skerry
