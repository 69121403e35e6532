// The twin-vs-recording test (twin_fidelity.h) on runs whose relation is known: the recording
// one more noise realisation of the twins' truth (not rejected, p spread over (0, 1]), and a
// recording whose estimates sit 3 sigma off (rejected on that block only). The twin pairs'
// mean AHED sits at the closed-form floor.

#include "skerry/twin/twin_fidelity.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

namespace skerry {
namespace {

// A run: 150 epochs, each state the truth (zero) plus N(0, (scale sigma)^2), reported with
// P = diag(sigma^2); `position_offset` moves every position by that many sigma east.
std::vector<EstimateRecord> SimulatedRun(std::mt19937_64* rng,
                                         double position_offset,
                                         double error_scale = 1.0) {
  std::normal_distribution<double> n01;
  std::vector<EstimateRecord> out;
  for (int k = 0; k < 150; ++k) {
    EstimateRecord r;
    r.state.t_ns = SecondsToNs(0.1 * k);
    Eigen::Matrix<double, 15, 1> sigma;
    sigma << 0.01, 0.01, 0.02, 0.5, 0.5, 1.0, 0.1, 0.1, 0.1, 1e-4, 1e-4, 1e-4, 1e-2, 1e-2, 1e-2;
    Eigen::Matrix<double, 15, 1> e;
    for (int i = 0; i < 15; ++i) e[i] = error_scale * sigma[i] * n01(*rng);
    e[3] += position_offset * sigma[3];
    r.state.q_w_b =
        Eigen::Quaterniond(Eigen::AngleAxisd(e.head<3>().norm(), e.head<3>().normalized()));
    r.state.p_w_b = e.segment<3>(3);
    r.state.v_w = e.segment<3>(6);
    r.state.bg = e.segment<3>(9);
    r.state.ba = e.segment<3>(12);
    r.has_covariance = true;
    r.covariance = sigma.cwiseAbs2().asDiagonal();
    out.push_back(r);
  }
  return out;
}

TEST(TwinFidelity, ARecordingThatIsOneMoreTwinIsNotRejected) {
  int rejected = 0;
  double p_sum = 0.0;
  for (int trial = 0; trial < 10; ++trial) {
    std::mt19937_64 rng(100 + trial);
    const std::vector<EstimateRecord> real = SimulatedRun(&rng, 0.0);
    std::vector<std::vector<EstimateRecord>> twins;
    for (int k = 0; k < 19; ++k) twins.push_back(SimulatedRun(&rng, 0.0));
    const TwinFidelity f = CompareWithTwins(real, twins, 0.1);
    const TwinFidelityBlock& pos = f.blocks[static_cast<int>(FidelityBlock::kPosition)];
    rejected += pos.indistinguishable ? 0 : 1;
    EXPECT_LT(std::abs(pos.z), 4.0);
    p_sum += pos.p_value;
    EXPECT_EQ(pos.epochs, 150);
    // Runs that differ by their noise only sit at the floor, 0.646 for a 3-D block.
    EXPECT_NEAR(pos.twins_ahed, pos.floor, 0.03);
    EXPECT_NEAR(pos.real_ahed, pos.floor, 0.05);
    EXPECT_LT(pos.real_covdiff, 1e-9);  // the same covariances
    // Over time: every epoch of the recording with all twins, the mean HED there.
    EXPECT_DOUBLE_EQ(f.coverage, 1.0);
    ASSERT_EQ(f.t_ns.size(), 150u);
    EXPECT_EQ(f.twins_valid[17], 19);
    double mean = 0.0;
    for (double h : f.hed_over_time[static_cast<int>(FidelityBlock::kPosition)]) mean += h / 150;
    EXPECT_NEAR(mean, pos.real_ahed, 1e-9);
  }
  // Each trial rejects with probability 0.1: 10 trials reject at most 4 times but for 1e-3.
  EXPECT_LE(rejected, 4);
  EXPECT_GT(p_sum / 10, 0.3);  // two-sided ranks of 20: mean p about 0.55
}

TEST(TwinFidelity, ARecordingThreeSigmaOffIsRejectedOnThatBlockOnly) {
  std::mt19937_64 rng(7);
  const std::vector<EstimateRecord> real = SimulatedRun(&rng, 3.0);
  std::vector<std::vector<EstimateRecord>> twins;
  for (int k = 0; k < 19; ++k) twins.push_back(SimulatedRun(&rng, 0.0));
  const TwinFidelity f = CompareWithTwins(real, twins, 0.1);
  const TwinFidelityBlock& pos = f.blocks[static_cast<int>(FidelityBlock::kPosition)];
  EXPECT_FALSE(pos.indistinguishable);
  EXPECT_DOUBLE_EQ(pos.p_value, 0.1);  // the farthest of 20: 2 x 1 / 20
  EXPECT_GT(pos.z, 4.0);
  EXPECT_GT(pos.real_ahed, pos.twins_max);
  EXPECT_GT(pos.real_meandiff, 0.5);
  // The other blocks are as any twin's (each rank test rejects 1 in 10 of those by chance, so
  // the check is on how far out the recording lies).
  EXPECT_LT(std::abs(f.blocks[static_cast<int>(FidelityBlock::kVelocity)].z), 3.5);
  EXPECT_LT(std::abs(f.blocks[static_cast<int>(FidelityBlock::kBiases)].z), 3.5);
  // The matrix is symmetric with a zero diagonal.
  const auto& A = f.ahed[static_cast<int>(FidelityBlock::kPosition)];
  EXPECT_EQ(A[0][0], 0.0);
  EXPECT_EQ(A[2][5], A[5][2]);
}

// Twins noisier than the recording (their estimates scatter twice as far about the truth): the
// recording is the run closest to all others, and the two-sided test rejects that too.
TEST(TwinFidelity, TwinsNoisierThanTheRecordingAreRejected) {
  std::mt19937_64 rng(8);
  const std::vector<EstimateRecord> real = SimulatedRun(&rng, 0.0);
  std::vector<std::vector<EstimateRecord>> twins;
  for (int k = 0; k < 19; ++k) twins.push_back(SimulatedRun(&rng, 0.0, 2.0));
  const TwinFidelity f = CompareWithTwins(real, twins, 0.1);
  const TwinFidelityBlock& pos = f.blocks[static_cast<int>(FidelityBlock::kPosition)];
  EXPECT_FALSE(pos.indistinguishable);
  EXPECT_LT(pos.real_ahed, pos.twins_ahed);
  EXPECT_LT(pos.z, -2.0);
}

// A twin that starts late covers only part of the recording; the epochs before have no distance.
TEST(TwinFidelity, CoverageCountsTheEpochsBothRunsHave) {
  std::mt19937_64 rng(9);
  const std::vector<EstimateRecord> real = SimulatedRun(&rng, 0.0);
  std::vector<std::vector<EstimateRecord>> twins;
  for (int k = 0; k < 3; ++k) {
    std::vector<EstimateRecord> t = SimulatedRun(&rng, 0.0);
    t.erase(t.begin(), t.begin() + 50);  // starts at the 51st epoch
    twins.push_back(t);
  }
  const TwinFidelity f = CompareWithTwins(real, twins);
  EXPECT_NEAR(f.coverage, 100.0 / 150.0, 1e-12);
  EXPECT_EQ(f.twins_valid[10], 0);
  EXPECT_TRUE(std::isnan(f.hed_over_time[0][10]));
  EXPECT_EQ(f.twins_valid[60], 3);
}

TEST(TwinFidelity, RefusesTooFewTwinsOrABadLevel) {
  std::mt19937_64 rng(1);
  const std::vector<EstimateRecord> r = SimulatedRun(&rng, 0.0);
  EXPECT_THROW(CompareWithTwins(r, {r}), std::invalid_argument);
  EXPECT_THROW(CompareWithTwins(r, {r, r}, 0.0), std::invalid_argument);
  EXPECT_THROW(CompareWithTwins(r, {r, r}, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace skerry
