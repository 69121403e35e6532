// HouseholderTriangularize against Eigen's dense HouseholderQR on stacks shaped like the square-
// root eliminations' (triangular carried rows, factor rows dense on a few columns), and on the
// cases its row band has to get right: unsorted rows, wide stacks, zero columns, a column that is
// already reduced.

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <random>

#include "skerry/solvers/householder_triangularize.h"

namespace skerry {
namespace {

// A stack as EliminateKeyframe builds it: `carried` upper-triangular rows on the first columns
// and the last `arrow` columns, then factor rows dense on the first `dense_cols` columns and the
// arrow, with diagonal scales from 1e-4 to 1e6.
Eigen::MatrixXd Stack(
    int carried, int factor_rows, int dense_cols, int cols, int arrow, std::mt19937* rng) {
  std::normal_distribution<double> normal;
  const int m = carried + factor_rows;
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(m, cols);
  const int chain = cols - arrow;
  for (int i = 0; i < carried; ++i) {
    for (int j = 0; j < cols; ++j) {
      const bool carried_col = (j < chain && j >= i && j < carried - arrow) || j >= chain;
      if (carried_col && (j >= i || j >= chain)) M(i, j) = normal(*rng);
    }
  }
  for (int i = carried; i < m; ++i) {
    for (int j = 0; j < dense_cols; ++j) M(i, j) = normal(*rng);
    for (int j = chain; j < cols; ++j) M(i, j) = normal(*rng);
  }
  Eigen::VectorXd scale(cols);
  for (int j = 0; j < cols; ++j) scale(j) = std::pow(10.0, -4.0 + 10.0 * j / (cols - 1.0));
  return M * scale.asDiagonal();
}

// R^T R = M^T M (relative to the scales of M^T M), zeros below the diagonal, and |R| equal to
// the dense QR's R row by row up to sign in its first `unique_rows` rows (those whose leading
// columns M determines: past a rank deficiency R is not unique).
void ExpectSameR(const Eigen::MatrixXd& M, Eigen::Index unique_rows) {
  Eigen::MatrixXd R = M;
  HouseholderTriangularize(&R);
  ASSERT_EQ(R.rows(), M.rows());
  ASSERT_EQ(R.cols(), M.cols());
  for (Eigen::Index j = 0; j < R.cols(); ++j) {
    for (Eigen::Index i = j + 1; i < R.rows(); ++i) ASSERT_EQ(R(i, j), 0.0) << i << "," << j;
  }
  const Eigen::MatrixXd H = M.transpose() * M;
  const Eigen::MatrixXd H_R = R.transpose() * R;
  const Eigen::VectorXd d = H.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  EXPECT_LT((d.asDiagonal() * (H_R - H) * d.asDiagonal()).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::MatrixXd dense = Eigen::HouseholderQR<Eigen::MatrixXd>(M).matrixQR();
  for (Eigen::Index i = 0; i < unique_rows; ++i) {
    const double sign = (R(i, i) < 0) == (dense(i, i) < 0) ? 1.0 : -1.0;
    const Eigen::RowVectorXd a = R.row(i).tail(M.cols() - i);
    const Eigen::RowVectorXd b = sign * dense.row(i).tail(M.cols() - i);
    EXPECT_LT((a - b).norm(), 1e-9 * b.norm()) << "row " << i;
  }
}

TEST(HouseholderTriangularize, MatchesTheDenseQrOnEliminationStacks) {
  std::mt19937 rng(7);
  // EliminateKeyframe's stack: 27 carried rows on [k | arrow], 15 IMU rows on [k | k+1 | arrow],
  // 3 GNSS rows on k; 45 columns. The 15 IMU rows determine only 15 of k+1's 18 columns, so R
  // is unique in its first 18 + 15 rows (the elimination keeps the first 18).
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::MatrixXd M = Stack(27, 15, 36, 45, 9, &rng);
    Eigen::MatrixXd gnss = Eigen::MatrixXd::Zero(3, 45);
    gnss.block(0, 3, 3, 3) = Eigen::Matrix3d::Random();
    Eigen::MatrixXd stacked(M.rows() + 3, 45);
    stacked << M, gnss;
    ExpectSameR(stacked, 33);
  }
}

TEST(HouseholderTriangularize, OrdersRowsItself) {
  std::mt19937 rng(11);
  Eigen::MatrixXd M = Stack(20, 24, 36, 40, 4, &rng);
  // Dense rows last, triangular rows reversed: the band is only right once the rows are sorted.
  Eigen::MatrixXd shuffled(M.rows(), M.cols());
  for (Eigen::Index i = 0; i < M.rows(); ++i) shuffled.row(i) = M.row(M.rows() - 1 - i);
  ExpectSameR(shuffled, 40);
  Eigen::MatrixXd R1 = M, R2 = shuffled;
  HouseholderTriangularize(&R1);
  HouseholderTriangularize(&R2);
  EXPECT_LT((R1.cwiseAbs() - R2.cwiseAbs()).cwiseAbs().maxCoeff(), 1e-9 * R1.cwiseAbs().maxCoeff());
}

TEST(HouseholderTriangularize, WideStacksZeroColumnsAndReducedColumns) {
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  // Fewer rows than columns: R is the whole (trapezoidal) stack.
  Eigen::MatrixXd wide(10, 25);
  for (Eigen::Index i = 0; i < wide.size(); ++i) wide.data()[i] = normal(rng);
  ExpectSameR(wide, 10);
  // A column of zeros (a block no factor here touches): rank deficient, R^T R still M^T M.
  Eigen::MatrixXd zero_col = Stack(10, 8, 16, 20, 2, &rng);
  zero_col.col(5).setZero();
  ExpectSameR(zero_col, 5);
  // A column with nothing below its diagonal is left as it is.
  Eigen::MatrixXd reduced = Eigen::MatrixXd::Zero(6, 4);
  reduced(0, 0) = -2.0;
  reduced.block(0, 1, 6, 3).setRandom();
  Eigen::MatrixXd R = reduced;
  HouseholderTriangularize(&R);
  EXPECT_EQ(R(0, 0), -2.0);
  ExpectSameR(reduced, 4);
  // Empty and single-row stacks.
  Eigen::MatrixXd empty(0, 5);
  HouseholderTriangularize(&empty);
  EXPECT_EQ(empty.rows(), 0);
  Eigen::MatrixXd one = Eigen::MatrixXd::Random(1, 5);
  const Eigen::MatrixXd one_before = one;
  HouseholderTriangularize(&one);
  EXPECT_EQ(one, one_before);
}

// The least-squares solution from R (with the residual as the last column) equals the dense
// solve's: what MarginalizeOldest's prior keeps.
TEST(HouseholderTriangularize, KeepsTheLeastSquaresSolution) {
  std::mt19937 rng(5);
  Eigen::MatrixXd A = Stack(18, 20, 33, 36, 3, &rng);
  Eigen::VectorXd b = Eigen::VectorXd::Random(A.rows());
  Eigen::MatrixXd Ab(A.rows(), A.cols() + 1);
  Ab << A, b;
  HouseholderTriangularize(&Ab);
  const Eigen::Index n = A.cols();
  const Eigen::VectorXd x =
      Ab.topLeftCorner(n, n).triangularView<Eigen::Upper>().solve(Ab.col(n).head(n));
  const Eigen::VectorXd x_dense = A.colPivHouseholderQr().solve(b);
  const Eigen::VectorXd scale = A.colwise().norm().transpose();
  EXPECT_LT((scale.asDiagonal() * (x - x_dense)).norm(), 1e-8 * b.norm());
  // The part of |b| no x explains: the residual column below R.
  EXPECT_NEAR(Ab.col(n).tail(A.rows() - n).norm(), (A * x_dense - b).norm(), 1e-9 * b.norm());
}

}  // namespace
}  // namespace skerry
