#include "skerry/eval/evaluation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "skerry/core/chi_square.h"
#include "skerry/core/heading.h"
#include "skerry/core/so3.h"

namespace skerry {
namespace {

// A level circle at 10 Hz for 100 s, heading along the track.
std::vector<StampedPose> CircleTruth() {
  std::vector<StampedPose> truth;
  for (int k = 0; k <= 1000; ++k) {
    const double t = 0.1 * k;
    const double a = 0.05 * t;
    StampedPose p;
    p.t_ns = SecondsToNs(t);
    p.p_w_b = Eigen::Vector3d(50.0 * std::cos(a), 50.0 * std::sin(a), 0.01 * t);
    p.q_w_b = ExpQ(Eigen::Vector3d(0.02 * std::sin(t), 0.01, a + M_PI / 2.0));
    truth.push_back(p);
  }
  return truth;
}

EstimateRecord RecordFrom(const StampedPose& truth,
                          const Eigen::Vector3d& dp,
                          const Eigen::Vector3d& dtheta) {
  EstimateRecord r;
  r.state.t_ns = truth.t_ns;
  r.state.p_w_b = truth.p_w_b + dp;
  r.state.q_w_b = ExpQ(dtheta) * truth.q_w_b;  // world-frame (left) perturbation
  return r;
}

TEST(EvaluationTest, StatsOfKnownValues) {
  const Stats s = ComputeStats({3.0, -4.0, 1.0, 0.0});
  EXPECT_EQ(s.count, 4);
  EXPECT_NEAR(s.rmse, std::sqrt(26.0 / 4.0), 1e-15);
  EXPECT_NEAR(s.mean, 0.0, 1e-15);
  EXPECT_NEAR(s.median, 0.5, 1e-15);
  EXPECT_EQ(s.max, 3.0);
  EXPECT_EQ(ComputeStats({2.0, 7.0, 1.0}).median, 2.0);
  EXPECT_EQ(ComputeStats({}).count, 0);
  // Type-7 percentiles: rank p/100 * (n - 1), interpolated (numpy's default).
  EXPECT_DOUBLE_EQ(Percentile({4.0, 1.0, 3.0, 2.0}, 50.0), 2.5);
  EXPECT_DOUBLE_EQ(Percentile({4.0, 1.0, 3.0, 2.0}, 95.0), 3.85);
  EXPECT_DOUBLE_EQ(Percentile({4.0, 1.0, 3.0, 2.0}, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(Percentile({4.0, 1.0, 3.0, 2.0}, 100.0), 4.0);
  EXPECT_DOUBLE_EQ(Percentile({7.0}, 95.0), 7.0);
  EXPECT_TRUE(std::isnan(Percentile({}, 50.0)));
}

TEST(EvaluationTest, ConstantOffsetGivesKnownErrors) {
  const std::vector<StampedPose> truth = CircleTruth();
  std::vector<EstimateRecord> estimate;
  // Estimates at 20 Hz (half of them between truth samples), alternating signs in east.
  for (int k = 0; k < 2000; ++k) {
    StampedPose t;
    ASSERT_TRUE(InterpolatePose(truth, SecondsToNs(0.05 * k), &t));
    const double s = (k % 2 == 0) ? 1.0 : -1.0;
    estimate.push_back(
        RecordFrom(t, Eigen::Vector3d(3.0 * s, 4.0, 12.0), Eigen::Vector3d(0.0, 0.0, 0.01)));
  }
  estimate.push_back(RecordFrom(truth.back(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()));
  estimate.back().state.t_ns += 1;  // just after the truth: unmatched
  const EvaluationResult r = Evaluate(estimate, truth, 1.0);
  EXPECT_EQ(r.unmatched, 1);
  ASSERT_EQ(r.epochs.size(), 2000u);
  EXPECT_NEAR(r.horizontal.rmse, 5.0, 1e-6);
  EXPECT_NEAR(r.vertical.rmse, 12.0, 1e-6);
  EXPECT_NEAR(r.position3d.rmse, 13.0, 1e-6);
  EXPECT_NEAR(r.position3d.max, 13.0, 1e-6);
  EXPECT_NEAR(r.east.rmse, 3.0, 1e-6);
  EXPECT_NEAR(r.east.mean, 0.0, 1e-6);
  EXPECT_NEAR(r.east.max, 3.0, 1e-6);
  EXPECT_NEAR(r.north.mean, 4.0, 1e-6);
  // A counter-clockwise rotation about up by 0.01 rad turns the heading (clockwise) by -0.01.
  EXPECT_NEAR(r.epochs[7].heading_err_deg, -0.01 * 180.0 / M_PI, 1e-6);
  EXPECT_NEAR(r.heading_deg.rmse, 0.01 * 180.0 / M_PI, 1e-6);
  EXPECT_LT((r.epochs[7].rot_err_w - Eigen::Vector3d(0, 0, 0.01)).norm(), 1e-9);
  EXPECT_NEAR(r.roll_pitch_deg.max, 0.0, 1e-6);
  EXPECT_EQ(r.nees_count, 0);
  // RPE: the east error flips sign every 0.05 s but 1 s spans 20 samples (even): relative
  // translation error comes only from the 0.01 rad rotation of the 1 s displacement (~2.5 m).
  EXPECT_GT(r.rpe_trans_m.count, 1900);
  EXPECT_NEAR(r.rpe_rot_deg.max, 0.0, 1e-6);
  EXPECT_NEAR(r.rpe_trans_m.mean, 0.01 * 2.5, 1e-3);
}

TEST(EvaluationTest, RpeOfAConstantPoseOffsetIsZero) {
  const std::vector<StampedPose> truth = CircleTruth();
  std::vector<EstimateRecord> estimate;
  for (const StampedPose& t : truth) {
    estimate.push_back(RecordFrom(t, Eigen::Vector3d(1.0, 2.0, 3.0), Eigen::Vector3d::Zero()));
  }
  const EvaluationResult r = Evaluate(estimate, truth, 2.0);
  EXPECT_EQ(r.rpe_trans_m.count, 1001 - 20);
  EXPECT_NEAR(r.rpe_trans_m.max, 0.0, 1e-9);
  EXPECT_NEAR(r.rpe_rot_deg.max, 0.0, 1e-6);
}

TEST(EvaluationTest, HeadingErrorWraps) {
  std::vector<StampedPose> truth(2);
  truth[0].t_ns = 0;
  truth[1].t_ns = 1000;
  truth[0].q_w_b = truth[1].q_w_b = QuaternionFromRollPitchHeading(0, 0, 359.0 * M_PI / 180.0);
  EstimateRecord e;
  e.state.t_ns = 500;
  e.state.q_w_b = QuaternionFromRollPitchHeading(0, 0, 1.0 * M_PI / 180.0);
  const EvaluationResult r = Evaluate({e}, truth);
  ASSERT_EQ(r.epochs.size(), 1u);
  EXPECT_NEAR(r.epochs[0].heading_err_deg, 2.0, 1e-9);
  e.state.q_w_b = QuaternionFromRollPitchHeading(0, 0, 178.5 * M_PI / 180.0);
  EXPECT_NEAR(Evaluate({e}, truth).epochs[0].heading_err_deg, 179.5, 1e-9);
  e.state.q_w_b = QuaternionFromRollPitchHeading(0, 0, 179.5 * M_PI / 180.0);
  EXPECT_NEAR(Evaluate({e}, truth).epochs[0].heading_err_deg, -179.5, 1e-9);
}

TEST(EvaluationTest, NeesOfKnownError) {
  std::vector<StampedPose> truth(2);
  truth[1].t_ns = 1000;
  EstimateRecord e =
      RecordFrom(truth[0], Eigen::Vector3d(2.0, 0.0, 0.0), Eigen::Vector3d(0.0, 0.03, 0.0));
  e.has_covariance = true;
  e.covariance = StateCovariance::Identity();
  e.covariance.block<3, 3>(kPos, kPos) *= 4.0;
  e.covariance.block<3, 3>(kRot, kRot) *= 0.01 * 0.01;
  const EvaluationResult r = Evaluate({e}, truth);
  ASSERT_TRUE(r.epochs[0].has_nees);
  EXPECT_NEAR(r.epochs[0].nees_pos, 1.0, 1e-12);
  EXPECT_NEAR(r.epochs[0].nees_pose, 1.0 + 9.0, 1e-9);
  EXPECT_NEAR(r.epochs[0].nees_horizontal, 1.0, 1e-12);
  EXPECT_EQ(r.nees_count, 1);
  EXPECT_NEAR(r.anees_pos, 1.0, 1e-12);
}

// The horizontal NEES sees the east-north error against the horizontal covariance alone: a
// vertical error counts in the 3-DOF NEES only.
TEST(EvaluationTest, HorizontalNeesLeavesTheVerticalOut) {
  std::vector<StampedPose> truth(2);
  truth[1].t_ns = 1000;
  EstimateRecord e = RecordFrom(truth[0], Eigen::Vector3d(0.0, 1.0, 10.0), Eigen::Vector3d::Zero());
  e.has_covariance = true;
  e.covariance = StateCovariance::Identity();
  e.covariance(kPos, kPos + 1) = e.covariance(kPos + 1, kPos) = 0.5;  // correlated east-north
  const EvaluationResult r = Evaluate({e}, truth);
  ASSERT_TRUE(r.epochs[0].has_nees);
  // [0 1] [1 .5; .5 1]^-1 [0 1]^T = 1 / 0.75.
  EXPECT_NEAR(r.epochs[0].nees_horizontal, 1.0 / 0.75, 1e-12);
  EXPECT_NEAR(r.epochs[0].nees_pos, 1.0 / 0.75 + 100.0, 1e-9);
  const NeesTest h = MonteCarloNeesTest({&r}, 1, 0.95, 0, /*horizontal=*/true);
  EXPECT_NEAR(h.time_average, 1.0 / 0.75, 1e-12);
}

// Errors drawn from N(0, P) with a correlated P: the ANEES must be near the DOF and inside the
// chi-square bounds.
TEST(EvaluationTest, ConsistentEstimatorHasAneesWithinBounds) {
  const std::vector<StampedPose> truth = CircleTruth();
  std::mt19937 rng(42);
  std::normal_distribution<double> normal;
  std::vector<EstimateRecord> estimate;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    Eigen::Matrix<double, 15, 15> a;
    for (int i = 0; i < 15; ++i) {
      for (int j = 0; j < 15; ++j) a(i, j) = 0.1 * normal(rng);
    }
    StateCovariance P = a * a.transpose() + 1e-3 * StateCovariance::Identity();
    P.block<3, 3>(kRot, kRot) *= 1e-2;  // rotations of a few degrees
    P.block<3, 3>(kRot, kPos) *= 1e-1;
    P.block<3, 3>(kPos, kRot) *= 1e-1;
    const Eigen::Matrix<double, 6, 6> P6 = P.block<6, 6>(0, 0);
    Eigen::Matrix<double, 6, 1> z;
    for (int i = 0; i < 6; ++i) z[i] = normal(rng);
    const Eigen::Matrix<double, 6, 1> x = Eigen::LLT<Eigen::Matrix<double, 6, 6>>(P6).matrixL() * z;
    EstimateRecord e = RecordFrom(truth[k], x.tail<3>(), x.head<3>());
    e.has_covariance = true;
    e.covariance = P;
    estimate.push_back(e);
  }
  const EvaluationResult r = Evaluate(estimate, truth);
  ASSERT_EQ(r.nees_count, 1001);
  const auto [lo3, hi3] = AneesBounds(3, r.nees_count, 0.999);
  const auto [lo6, hi6] = AneesBounds(6, r.nees_count, 0.999);
  EXPECT_GT(r.anees_pos, lo3);
  EXPECT_LT(r.anees_pos, hi3);
  EXPECT_GT(r.anees_pose, lo6);
  EXPECT_LT(r.anees_pose, hi6);
  // Overconfident (covariance 4x too small): the ANEES is ~4x the DOF, far outside.
  for (EstimateRecord& e : estimate) e.covariance /= 4.0;
  EXPECT_GT(Evaluate(estimate, truth).anees_pos, hi3);
}

TEST(EvaluationTest, AneesBounds) {
  const auto [lo, hi] = AneesBounds(3, 1, 0.95);
  EXPECT_NEAR(lo, 0.215795, 1e-6);
  EXPECT_NEAR(hi, 9.348404, 1e-6);
  const auto [lo_n, hi_n] = AneesBounds(6, 100, 0.95);
  EXPECT_NEAR(lo_n, ChiSquareQuantile(0.025, 600) / 100.0, 1e-12);
  EXPECT_NEAR(hi_n, ChiSquareQuantile(0.975, 600) / 100.0, 1e-12);
  EXPECT_LT(lo_n, 6.0);
  EXPECT_GT(hi_n, 6.0);
  EXPECT_TRUE(std::isnan(AneesBounds(3, 0.0).first));  // no samples: no bounds
  EXPECT_TRUE(std::isnan(AneesBounds(3, 0.0).second));
}

// One run's ANEES with correlated epochs: the errors of a consistent estimator as a 3-D AR(1)
// process with unit covariance (phi 0.98 between keyframes, as a slowly wandering position
// error), 2000 epochs, 400 runs. The plain chi-square bounds treat 2000 epochs as independent
// and reject most of these consistent runs; the bounds of the effective sample size contain the
// ANEES about 95 % of the time.
TEST(EvaluationTest, AneesBoundsOfCorrelatedEpochs) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double phi = 0.98;
  const int epochs = 2000, runs = 400;
  int inside_plain = 0, inside_effective = 0;
  double sum_neff = 0.0;
  for (int r = 0; r < runs; ++r) {
    Eigen::Vector3d e(normal(rng), normal(rng), normal(rng));
    std::vector<double> nees;
    for (int k = 0; k < epochs; ++k) {
      e = phi * e +
          std::sqrt(1.0 - phi * phi) * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
      nees.push_back(e.squaredNorm());
    }
    double anees = 0.0;
    for (double v : nees) anees += v / epochs;
    const auto plain = AneesBounds(3, epochs);
    const double n_eff = EffectiveSampleSize(nees);
    sum_neff += n_eff;
    const auto eff = AneesBounds(3, n_eff);
    inside_plain += anees >= plain.first && anees <= plain.second;
    inside_effective += anees >= eff.first && anees <= eff.second;
  }
  // The NEES autocorrelation is phi^(2k): tau = (1 + phi^2) / (1 - phi^2) = 49.5, N_eff = 40;
  // estimated from 2000 samples, tau comes out short by the usual finite-sample bias (~20 %).
  EXPECT_NEAR(sum_neff / runs, epochs / ((1 + phi * phi) / (1 - phi * phi)), 0.25 * 40.4);
  EXPECT_LT(inside_plain, runs / 3);
  EXPECT_NEAR(static_cast<double>(inside_effective) / runs, 0.95, 0.035);
  // Independent samples are worth themselves; a constant series counts as independent.
  std::vector<double> white;
  for (int k = 0; k < 4000; ++k) white.push_back(normal(rng) * normal(rng));
  EXPECT_GT(EffectiveSampleSize(white), 3000.0);
  EXPECT_EQ(EffectiveSampleSize(std::vector<double>(10, 2.0)), 10.0);
}

// An epoch with a position NEES, for the Monte-Carlo test.
EpochError NeesEpoch(TimeNs t, double nees) {
  EpochError e;
  e.t_ns = t;
  e.has_nees = true;
  e.nees_pos = nees;
  return e;
}

TEST(EvaluationTest, MonteCarloNeesTestCountsEpochsAgainstTheirBounds) {
  // Two runs; epoch 1 in both (mean 3: inside), epoch 2 in both (mean 40: above), epoch 3 in
  // both (mean 0.01: below), epoch 4 in one run only (NEES 3).
  EvaluationResult a, b;
  a.epochs = {NeesEpoch(1, 2.0), NeesEpoch(2, 40.0), NeesEpoch(3, 0.01), NeesEpoch(4, 3.0)};
  b.epochs = {NeesEpoch(1, 4.0), NeesEpoch(2, 40.0), NeesEpoch(3, 0.01)};
  EpochError no_nees;
  no_nees.t_ns = 5;
  b.epochs.push_back(no_nees);  // no covariance there: not tested
  const NeesTest all = MonteCarloNeesTest({&a, &b});
  EXPECT_EQ(all.epochs, 4);
  EXPECT_DOUBLE_EQ(all.inside, 0.5);  // epochs 1 and 4 (its own one-run bounds)
  EXPECT_DOUBLE_EQ(all.above, 0.25);
  EXPECT_DOUBLE_EQ(all.below, 0.25);
  EXPECT_NEAR(all.time_average, (3.0 + 40.0 + 0.01 + 3.0) / 4.0, 1e-12);
  const NeesTest shared = MonteCarloNeesTest({&a, &b}, 2);
  EXPECT_EQ(shared.epochs, 3);
  EXPECT_NEAR(shared.inside, 1.0 / 3.0, 1e-12);
  EXPECT_EQ(MonteCarloNeesTest({}).epochs, 0);
}

TEST(EvaluationTest, MonteCarloNeesTestBinsRunsOnTheKeyframeGrid) {
  // Keyframes of two seeds stamped a few milliseconds apart (their first fixes differ): with a
  // 100 ms grid, 0.098 s and 0.103 s are one epoch, 0.196 s and 0.204 s another, 0.349 s and
  // 0.351 s fall on either side of 0.35 s (bins 0.3 and 0.4). A run's second keyframe in one bin
  // does not count twice.
  const TimeNs ms = 1'000'000;
  EvaluationResult a, b;
  a.epochs = {NeesEpoch(98 * ms, 2.0), NeesEpoch(196 * ms, 40.0), NeesEpoch(349 * ms, 3.0)};
  b.epochs = {NeesEpoch(103 * ms, 4.0), NeesEpoch(120 * ms, 1000.0), NeesEpoch(204 * ms, 40.0),
              NeesEpoch(351 * ms, 3.0)};
  const NeesTest t = MonteCarloNeesTest({&a, &b}, 1, 0.95, 100 * ms);
  EXPECT_EQ(t.epochs, 4);  // 0.1, 0.2, 0.3, 0.4
  const NeesTest shared = MonteCarloNeesTest({&a, &b}, 2, 0.95, 100 * ms);
  EXPECT_EQ(shared.epochs, 2);                                  // 0.1 and 0.2
  EXPECT_NEAR(shared.time_average, (3.0 + 40.0) / 2.0, 1e-12);  // b's 0.12 s left out
  EXPECT_EQ(MonteCarloNeesTest({&a, &b}, 2).epochs, 0);         // no grid: nothing shared
}

}  // namespace
}  // namespace skerry
