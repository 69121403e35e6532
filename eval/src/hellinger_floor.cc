#include "skerry/eval/hellinger_floor.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace skerry {

HellingerFloor ConsistentRunsHellingerFloor(int dimension) {
  if (dimension < 1) throw std::invalid_argument("ConsistentRunsHellingerFloor: dimension < 1");
  const double k = dimension;
  // E[f(q)], q ~ chi2_k, with q = u^2: the density of u is 2 u^(k-1) exp(-u^2/2) / (2^(k/2)
  // Gamma(k/2)), smooth on [0, inf) for every k >= 1 (the chi-square's x^(k/2-1) is not, at k = 1).
  // Composite Simpson over u in [0, sqrt(k) + 12] (the density beyond is below 1e-30).
  const double log_norm = std::log(2.0) - 0.5 * k * std::log(2.0) - std::lgamma(0.5 * k);
  const double u_max = std::sqrt(k) + 12.0;
  const int n = 20000;  // even
  const double h = u_max / n;
  double s0 = 0.0, s1 = 0.0, s2 = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double u = i * h;
    const double density = u > 0.0 ? std::exp(log_norm + (k - 1.0) * std::log(u) - 0.5 * u * u)
                                   : (dimension == 1 ? std::exp(log_norm) : 0.0);
    const double hed2 = -std::expm1(-0.25 * u * u);
    const double w = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    s0 += w * density;
    s1 += w * density * std::sqrt(hed2);
    s2 += w * density * hed2;
  }
  HellingerFloor f;
  f.dimension = dimension;
  f.mean_hed = s1 / s0;  // s0 = 1 up to the quadrature's error, which this ratio cancels
  f.mean_hed2 = s2 / s0;
  f.sd_hed = std::sqrt(std::max(0.0, f.mean_hed2 - f.mean_hed * f.mean_hed));
  return f;
}

}  // namespace skerry
