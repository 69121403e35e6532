#include "skerry/twin/drift_detection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace skerry {
namespace {

constexpr double kProbeTausS[] = {3.0, 30.0, 300.0};

bool FiniteNonNegative(double x) { return std::isfinite(x) && x >= 0.0; }

// Standard normals by Box-Muller from the top 53 bits of std::mt19937_64 (fully specified by the
// standard, unlike std::normal_distribution), both values used.
class Normals {
 public:
  explicit Normals(std::uint64_t seed) : engine_(seed) {}
  double Next() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - Uniform();  // (0, 1]: the log is finite
    const double u2 = Uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * 3.14159265358979323846 * u2;
    spare_ = radius * std::sin(angle);
    has_spare_ = true;
    return radius * std::cos(angle);
  }

 private:
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

// Sum of squares about the mean of the selected components (axes [first, first + count)) of `x`.
double SumOfSquaresAboutMean(const std::vector<Eigen::Vector3d>& x, int first, int count) {
  double ss = 0.0;
  for (int a = first; a < first + count; ++a) {
    double mean = 0.0;
    for (const Eigen::Vector3d& v : x) mean += v[a];
    mean /= static_cast<double>(x.size());
    for (const Eigen::Vector3d& v : x) ss += (v[a] - mean) * (v[a] - mean);
  }
  return ss;
}

double RootOfRatio(double num, double den) { return den > 0.0 ? std::sqrt(num / den) : 0.0; }

double Limit(double threshold, double gain) {
  return gain > 0.0 ? threshold / gain : std::numeric_limits<double>::infinity();
}

}  // namespace

std::vector<double> DriftProbeTaus(double span_s, double period_s) {
  if (!(std::isfinite(span_s) && span_s > 0.0) || !(std::isfinite(period_s) && period_s > 0.0)) {
    throw std::invalid_argument("DriftProbeTaus: span and period must be finite and > 0");
  }
  const double lo = 2.0 * period_s;
  const double hi = std::max(lo, 0.5 * span_s);
  std::vector<double> out;
  for (double tau : kProbeTausS) {
    const double t = std::clamp(tau, lo, hi);
    if (out.empty() || t > out.back() * (1.0 + 1e-9)) out.push_back(t);
  }
  return out;
}

std::vector<Eigen::Vector3d> GaussMarkovPerturbation(const std::vector<double>& t_s,
                                                     double tau_s,
                                                     double sigma_horizontal_m,
                                                     double sigma_vertical_m,
                                                     std::uint64_t seed) {
  const std::string where = "GaussMarkovPerturbation: ";
  if (!(std::isfinite(tau_s) && tau_s > 0.0))
    throw std::invalid_argument(where + "tau must be > 0");
  if (!FiniteNonNegative(sigma_horizontal_m) || !FiniteNonNegative(sigma_vertical_m)) {
    throw std::invalid_argument(where + "sigmas must be finite and >= 0");
  }
  for (std::size_t k = 0; k < t_s.size(); ++k) {
    if (!std::isfinite(t_s[k]) || (k > 0 && t_s[k] < t_s[k - 1])) {
      throw std::invalid_argument(where + "t_s[" + std::to_string(k) +
                                  "] not finite or before its predecessor");
    }
  }
  const Eigen::Vector3d sigma(sigma_horizontal_m, sigma_horizontal_m, sigma_vertical_m);
  Normals normals(seed);
  auto draw = [&]() {
    const double e = normals.Next(), n = normals.Next(), u = normals.Next();
    return Eigen::Vector3d(e, n, u);
  };
  std::vector<Eigen::Vector3d> out;
  out.reserve(t_s.size());
  for (std::size_t k = 0; k < t_s.size(); ++k) {
    if (k == 0) {
      out.push_back(sigma.cwiseProduct(draw()));  // the stationary distribution
      continue;
    }
    // Exact discretisation of dd/dt = -d / tau + w over the interval (Brown and Hwang 2012,
    // sec. 2.9): the stationary variance is kept whatever the interval.
    const double phi = std::exp(-(t_s[k] - t_s[k - 1]) / tau_s);
    out.push_back(phi * out.back() + std::sqrt(1.0 - phi * phi) * sigma.cwiseProduct(draw()));
  }
  return out;
}

DriftBatchGain MeasureBatchGain(const std::vector<PerturbedBatchRun>& runs) {
  const std::string where = "MeasureBatchGain: ";
  if (runs.empty()) throw std::invalid_argument(where + "no run");
  double in_h = 0.0, in_v = 0.0, out_h = 0.0, out_v = 0.0;
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const auto& d = runs[r].injected_enu_m;
    const auto& c = runs[r].residual_change_enu_m;
    const std::string run = "run " + std::to_string(r);
    if (d.size() != c.size() || d.size() < 2) {
      throw std::invalid_argument(where + run + " needs two vectors of equal length >= 2 (" +
                                  std::to_string(d.size()) + ", " + std::to_string(c.size()) + ")");
    }
    for (std::size_t i = 0; i < d.size(); ++i) {
      if (!d[i].allFinite() || !c[i].allFinite()) {
        throw std::invalid_argument(where + run + ", entry " + std::to_string(i) + " not finite");
      }
    }
    in_h += SumOfSquaresAboutMean(d, 0, 2);
    in_v += SumOfSquaresAboutMean(d, 2, 1);
    out_h += SumOfSquaresAboutMean(c, 0, 2);
    out_v += SumOfSquaresAboutMean(c, 2, 1);
  }
  DriftBatchGain g;
  g.horizontal = RootOfRatio(out_h, in_h);
  g.vertical = RootOfRatio(out_v, in_v);
  return g;
}

double DriftSeenThreshold(double white_sigma_m,
                          double drift_bootstrap_sigma_m,
                          double min_share_of_white,
                          double z) {
  if (!FiniteNonNegative(white_sigma_m) || !FiniteNonNegative(drift_bootstrap_sigma_m) ||
      !FiniteNonNegative(min_share_of_white) || !FiniteNonNegative(z)) {
    throw std::invalid_argument("DriftSeenThreshold: every argument must be finite and >= 0");
  }
  return std::max(min_share_of_white * white_sigma_m, z * drift_bootstrap_sigma_m);
}

DriftDetection DriftDetectionAt(double tau_s,
                                const DriftBatchGain& gain,
                                double threshold_horizontal_m,
                                double threshold_vertical_m) {
  DriftDetection d;
  d.tau_s = tau_s;
  d.batch_gain = gain;
  d.gain_limit_sigma_horizontal_m = Limit(threshold_horizontal_m, gain.horizontal);
  d.gain_limit_sigma_vertical_m = Limit(threshold_vertical_m, gain.vertical);
  d.detectable_sigma_horizontal_m = d.gain_limit_sigma_horizontal_m;
  d.detectable_sigma_vertical_m = d.gain_limit_sigma_vertical_m;
  return d;
}

GnssResidualSeries ScaledPerturbedResiduals(const GnssResidualSeries& before,
                                            const PerturbedBatchRun& run,
                                            double scale_horizontal,
                                            double scale_vertical) {
  const std::string where = "ScaledPerturbedResiduals: ";
  const std::size_t m = run.index.size();
  if (run.residual_change_enu_m.size() != m) {
    throw std::invalid_argument(where + "index and residual change differ in length");
  }
  if (before.e_enu_m.size() != before.t_s.size() || before.v_enu_m_s.size() != before.t_s.size()) {
    throw std::invalid_argument(where + "the residual series' vectors differ in length");
  }
  const Eigen::Vector3d scale(scale_horizontal, scale_horizontal, scale_vertical);
  GnssResidualSeries out;
  for (std::size_t j = 0; j < m; ++j) {
    const std::size_t i = run.index[j];
    if (i >= before.t_s.size() || (j > 0 && i <= run.index[j - 1])) {
      throw std::invalid_argument(where + "index[" + std::to_string(j) +
                                  "] out of range or not increasing");
    }
    out.t_s.push_back(before.t_s[i]);
    out.e_enu_m.push_back(before.e_enu_m[i] + scale.cwiseProduct(run.residual_change_enu_m[j]));
    out.v_enu_m_s.push_back(before.v_enu_m_s[i]);
  }
  return out;
}

DriftDetection ConfirmDetection(const DriftDetection& probe,
                                const std::vector<PerturbedBatchRun>& runs,
                                const GnssResidualSeries& before,
                                double injected_sigma_horizontal_m,
                                double injected_sigma_vertical_m,
                                const GnssFitFunction& fit,
                                int max_doublings) {
  DriftDetection out = probe;
  out.confirmed_horizontal = out.confirmed_vertical = false;
  double* limit[2] = {&out.detectable_sigma_horizontal_m, &out.detectable_sigma_vertical_m};
  const double injected[2] = {injected_sigma_horizontal_m, injected_sigma_vertical_m};
  bool* confirmed[2] = {&out.confirmed_horizontal, &out.confirmed_vertical};
  bool searching[2];
  for (int a = 0; a < 2; ++a) {
    searching[a] = std::isfinite(*limit[a]) && *limit[a] > 0.0 && injected[a] > 0.0;
  }
  for (int round = 0; round <= max_doublings && (searching[0] || searching[1]); ++round) {
    // Both axis pairs at their current levels (a pair not searched carries no added drift).
    double scale[2];
    for (int a = 0; a < 2; ++a) scale[a] = injected[a] > 0.0 ? *limit[a] / injected[a] : 0.0;
    for (int a = 0; a < 2; ++a) {
      if (!std::isfinite(scale[a])) scale[a] = 0.0;
    }
    int seen[2] = {0, 0};
    for (const PerturbedBatchRun& run : runs) {
      const GnssErrorModelFit f = fit(ScaledPerturbedResiduals(before, run, scale[0], scale[1]));
      seen[0] += f.drift_sigma_horizontal_m.identified;
      seen[1] += f.drift_sigma_vertical_m.identified;
    }
    for (int a = 0; a < 2; ++a) {
      if (!searching[a]) continue;
      if (2 * seen[a] > static_cast<int>(runs.size())) {
        *confirmed[a] = true;
        searching[a] = false;
      } else if (round < max_doublings) {
        *limit[a] *= 2.0;
      }
    }
  }
  return out;
}

void StateDriftDetectionLimit(const std::vector<DriftDetection>& probes, GnssErrorModelFit* fit) {
  if (probes.empty()) return;
  double limit_h = 0.0, limit_v = 0.0;
  for (const DriftDetection& p : probes) {
    limit_h = std::max(limit_h, p.detectable_sigma_horizontal_m);
    limit_v = std::max(limit_v, p.detectable_sigma_vertical_m);
  }
  if (!fit->drift_sigma_horizontal_m.identified) fit->drift_sigma_horizontal_m.sigma = limit_h;
  if (!fit->drift_sigma_vertical_m.identified) fit->drift_sigma_vertical_m.sigma = limit_v;
}

}  // namespace skerry
