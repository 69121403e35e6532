#include "skerry/solvers/householder_triangularize.h"

#include <Eigen/Householder>
#include <algorithm>
#include <numeric>
#include <vector>

namespace skerry {

void HouseholderTriangularize(Eigen::MatrixXd* M_ptr) {
  Eigen::MatrixXd& M = *M_ptr;
  const Eigen::Index m = M.rows();
  const Eigen::Index n = M.cols();
  // Rows by leading nonzero column (stable: equal ones keep their order).
  std::vector<Eigen::Index> lead(static_cast<size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) {
    Eigen::Index c = 0;
    while (c < n && M(i, c) == 0.0) ++c;
    lead[static_cast<size_t>(i)] = c;
  }
  if (!std::is_sorted(lead.begin(), lead.end())) {
    std::vector<Eigen::Index> order(static_cast<size_t>(m));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&lead](Eigen::Index a, Eigen::Index b) {
      return lead[static_cast<size_t>(a)] < lead[static_cast<size_t>(b)];
    });
    // The sorted copy in a buffer this thread keeps: swapped with M, each keeps its storage, so
    // that a caller reusing M of one size allocates nothing here.
    static thread_local Eigen::MatrixXd sorted;
    sorted.resize(m, n);
    for (Eigen::Index i = 0; i < m; ++i) sorted.row(i) = M.row(order[static_cast<size_t>(i)]);
    M.swap(sorted);
  }
  const Eigen::Index size = std::min(m, n);
  for (Eigen::Index k = 0; k < size; ++k) {
    // Rows k..last hold column k's nonzeros: every row after `last` is zero in columns 0..k
    // (earlier columns were zeroed below their diagonal, or never had a nonzero there).
    Eigen::Index last = m - 1;
    while (last > k && M(last, k) == 0.0) --last;
    const Eigen::Index len = last - k + 1;
    if (len == 1) continue;  // nothing below the diagonal
    double tau = 0.0;
    double beta = 0.0;
    M.col(k).segment(k, len).makeHouseholderInPlace(tau, beta);
    M(k, k) = beta;
    // H = I - tau [1; v] [1; v]^T on columns k+1.. of rows k..last, column by column on the raw
    // storage: s = tau (x_0 + v^T x_rest), x_0 -= s, x_rest -= s v (Golub & Van Loan, 4th ed.,
    // Alg. 5.1.2 applied as in Alg. 5.2.1). Eigen's applyHouseholderOnTheLeft forms the same
    // from a product and an outer product of dynamic blocks, whose set-up cost more than the
    // arithmetic at these sizes (tens of rows).
    const double* v = M.col(k).data() + k + 1;
    const Eigen::Index rest = len - 1;
    for (Eigen::Index c = k + 1; c < n; ++c) {
      double* x = M.col(c).data() + k;
      double dot = x[0];
      for (Eigen::Index i = 0; i < rest; ++i) dot += v[i] * x[i + 1];
      const double s = tau * dot;
      if (s == 0.0) continue;
      x[0] -= s;
      for (Eigen::Index i = 0; i < rest; ++i) x[i + 1] -= s * v[i];
    }
    M.col(k).segment(k + 1, len - 1).setZero();
  }
}

}  // namespace skerry
