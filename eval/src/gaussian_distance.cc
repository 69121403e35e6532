#include "skerry/eval/gaussian_distance.h"

#include <Eigen/Cholesky>
#include <cmath>

namespace skerry {

namespace {

/// ln|P| = 2 sum ln L_ii of the Cholesky factor P = L L^T.
double LogDet(const Eigen::LLT<Eigen::MatrixXd>& llt) {
  return 2.0 * llt.matrixLLT().diagonal().array().log().sum();
}

}  // namespace

bool IsCovariance(const Eigen::MatrixXd& p) {
  if (p.rows() != p.cols() || p.rows() == 0 || !p.allFinite()) return false;
  const double scale = p.cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) return false;
  if ((p - p.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) return false;
  const Eigen::LLT<Eigen::MatrixXd> llt(p);
  return llt.info() == Eigen::Success && (llt.matrixLLT().diagonal().array() > 0.0).all();
}

GaussianDistance CompareGaussians(const Eigen::VectorXd& delta,
                                  const Eigen::MatrixXd& p1,
                                  const Eigen::MatrixXd& p2) {
  GaussianDistance d;
  const Eigen::Index n = delta.size();
  if (p1.rows() != n || p2.rows() != n || !delta.allFinite() || !IsCovariance(p1) ||
      !IsCovariance(p2)) {
    return d;
  }
  // Symmetrise exactly so the factorisations see the same matrix the formula means.
  const Eigen::MatrixXd s1 = 0.5 * (p1 + p1.transpose());
  const Eigen::MatrixXd s2 = 0.5 * (p2 + p2.transpose());
  const Eigen::MatrixXd pbar = 0.5 * (s1 + s2);
  const Eigen::LLT<Eigen::MatrixXd> llt1(s1), llt2(s2), llt_bar(pbar);
  if (llt_bar.info() != Eigen::Success) return d;
  // 1/2 ln(|Pbar| / sqrt(|P1||P2|)) >= 0 by the concavity of ln det; clamp rounding below 0.
  const double log_ratio =
      std::max(0.0, 0.5 * (LogDet(llt_bar) - 0.5 * (LogDet(llt1) + LogDet(llt2))));
  const double mahalanobis_sq = std::max(0.0, delta.dot(llt_bar.solve(delta)));
  d.bhattacharyya = 0.125 * mahalanobis_sq + log_ratio;
  d.hellinger_sq = -std::expm1(-d.bhattacharyya);
  d.hellinger = std::sqrt(d.hellinger_sq);
  d.covdiff = std::sqrt(-std::expm1(-log_ratio));
  d.meandiff = std::sqrt(-std::expm1(-0.125 * mahalanobis_sq));
  d.valid = true;
  return d;
}

}  // namespace skerry
