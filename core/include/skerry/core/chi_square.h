#pragma once
/// \file
/// Chi-square distribution: CDF through the regularised lower incomplete gamma function
/// (Numerical Recipes 3rd ed., sec. 6.2: series for x < a+1, continued fraction otherwise) and
/// the quantile by safeguarded Newton/bisection on it.

namespace skerry {

/// P(X <= x) for X ~ chi2(dof).
double ChiSquareCdf(double x, double dof);

/// x such that P(X <= x) = p, for X ~ chi2(dof), 0 < p < 1.
double ChiSquareQuantile(double p, double dof);

}  // namespace skerry
