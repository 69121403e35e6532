#include "skerry/core/chi_square.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace skerry {
namespace {

constexpr int kMaxIterations = 1000000;  // enough for a ~ 1e8 (terms fall off after ~sqrt(a))
constexpr double kEps = 1e-16;
constexpr double kTiny = std::numeric_limits<double>::min() / kEps;

// Series for P(a, x), valid and fast for x < a + 1 (Numerical Recipes 3rd ed. eq. 6.2.5).
double GammaPSeries(double a, double x) {
  const double gln = std::lgamma(a);
  double ap = a;
  double sum = 1.0 / a;
  double del = sum;
  for (int n = 0; n < kMaxIterations; ++n) {
    ap += 1.0;
    del *= x / ap;
    sum += del;
    if (std::fabs(del) < std::fabs(sum) * kEps) break;
  }
  return sum * std::exp(-x + a * std::log(x) - gln);
}

// Continued fraction for Q(a, x) = 1 - P(a, x), for x >= a + 1 (NR eq. 6.2.7, modified Lentz).
double GammaQContinuedFraction(double a, double x) {
  const double gln = std::lgamma(a);
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i < kMaxIterations; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1.0) <= kEps) break;
  }
  return std::exp(-x + a * std::log(x) - gln) * h;
}

// Regularised lower incomplete gamma P(a, x).
double GammaP(double a, double x) {
  if (x <= 0.0) return 0.0;
  if (x < a + 1.0) return GammaPSeries(a, x);
  return 1.0 - GammaQContinuedFraction(a, x);
}

double ChiSquarePdf(double x, double dof) {
  if (x <= 0.0) return 0.0;
  const double k = 0.5 * dof;
  return std::exp((k - 1.0) * std::log(x) - 0.5 * x - k * std::log(2.0) - std::lgamma(k));
}

}  // namespace

double ChiSquareCdf(double x, double dof) {
  if (!(dof > 0.0)) throw std::invalid_argument("ChiSquareCdf: dof must be positive");
  if (std::isnan(x)) return x;
  if (x <= 0.0) return 0.0;
  if (std::isinf(x)) return 1.0;
  return GammaP(0.5 * dof, 0.5 * x);
}

double ChiSquareQuantile(double p, double dof) {
  if (!(dof > 0.0)) throw std::invalid_argument("ChiSquareQuantile: dof must be positive");
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("ChiSquareQuantile: p must be in (0, 1)");
  // Bracket the root: CDF(lo) <= p <= CDF(hi).
  double lo = 0.0;
  double hi = std::max(1.0, dof);
  while (ChiSquareCdf(hi, dof) < p) {
    lo = hi;
    hi *= 2.0;
  }
  // Newton from the mean, falling back to bisection whenever a step leaves the bracket.
  double x = std::min(std::max(dof, 0.5 * (lo + hi)), hi);
  if (x <= lo) x = 0.5 * (lo + hi);
  for (int iter = 0; iter < 500; ++iter) {
    const double f = ChiSquareCdf(x, dof) - p;
    if (f == 0.0) return x;
    if (f < 0.0) {
      lo = x;
    } else {
      hi = x;
    }
    const double pdf = ChiSquarePdf(x, dof);
    double next = (pdf > 0.0) ? x - f / pdf : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    // Relative tolerances: quantiles for tiny p and small dof can be ~1e-20 or less.
    if (std::fabs(next - x) <= 1e-14 * x || hi - lo <= 1e-15 * hi) return next;
    x = next;
  }
  return x;
}

}  // namespace skerry
