// The floor of the Hellinger distance between two consistent runs (hellinger_floor.h): E[HED^2]
// against the chi-square moment generating function, E[HED] against a Monte-Carlo of two runs'
// Gaussians through the distance code itself (gaussian_distance.h), and the figures issue 15
// quotes.

#include "skerry/eval/hellinger_floor.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>

#include "skerry/eval/gaussian_distance.h"

namespace skerry {
namespace {

TEST(HellingerFloor, MeanSquareIsOneMinusOnePointFiveToTheMinusHalfK) {
  for (int k = 1; k <= 15; ++k) {
    const HellingerFloor f = ConsistentRunsHellingerFloor(k);
    EXPECT_NEAR(f.mean_hed2, 1.0 - std::pow(1.5, -0.5 * k), 1e-9) << k;
    EXPECT_GT(f.mean_hed, 0.0);
    EXPECT_LT(f.mean_hed * f.mean_hed, f.mean_hed2);  // Jensen: the spread is not zero
  }
  EXPECT_THROW(ConsistentRunsHellingerFloor(0), std::invalid_argument);
}

// Two runs: the truth 0, a random covariance S, each run's mean drawn from N(0, S) and reported
// with S; the HED of the two Gaussians averaged over many pairs.
TEST(HellingerFloor, MeanMatchesTwoSimulatedConsistentRuns) {
  std::mt19937_64 rng(15);
  std::normal_distribution<double> n01;
  for (int k : {1, 3, 4, 6}) {
    Eigen::MatrixXd A(k, k);
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j) A(i, j) = n01(rng);
    const Eigen::MatrixXd S = A * A.transpose() + 0.1 * Eigen::MatrixXd::Identity(k, k);
    const Eigen::MatrixXd L = S.llt().matrixL();
    const int draws = 40000;
    double sum = 0.0, sum2 = 0.0;
    for (int d = 0; d < draws; ++d) {
      Eigen::VectorXd z1(k), z2(k);
      for (int i = 0; i < k; ++i) {
        z1(i) = n01(rng);
        z2(i) = n01(rng);
      }
      const GaussianDistance g = CompareGaussians(L * z2 - L * z1, S, S);
      ASSERT_TRUE(g.valid);
      sum += g.hellinger;
      sum2 += g.hellinger * g.hellinger;
    }
    const double mean = sum / draws;
    const double sd = std::sqrt(sum2 / draws - mean * mean);
    const HellingerFloor f = ConsistentRunsHellingerFloor(k);
    EXPECT_NEAR(f.mean_hed, mean, 4.0 * sd / std::sqrt(draws)) << k;
    EXPECT_NEAR(f.sd_hed, sd, 0.02) << k;
  }
}

// Issue 15's Monte-Carlo figures: a perfect twin scores about what prior work measured.
TEST(HellingerFloor, TheFiguresPriorWorkMeasuredAreTheFloor) {
  EXPECT_NEAR(ConsistentRunsHellingerFloor(1).mean_hed, 0.36, 0.005);
  EXPECT_NEAR(ConsistentRunsHellingerFloor(3).mean_hed, 0.65, 0.005);
  EXPECT_NEAR(ConsistentRunsHellingerFloor(4).mean_hed, 0.73, 0.005);
  EXPECT_NEAR(ConsistentRunsHellingerFloor(6).mean_hed, 0.83, 0.005);
}

}  // namespace
}  // namespace skerry
