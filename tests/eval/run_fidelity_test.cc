// The fidelity of two runs: epoch matching, per-block differences in skerry's tangent space,
// averages and the share of epochs where only one run is valid.

#include "skerry/eval/run_fidelity.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "skerry/core/heading.h"
#include "skerry/core/so3.h"
#include "skerry/eval/hellinger_floor.h"

namespace skerry {
namespace {

double Hed2OneD(double d, double s1, double s2) {
  return 1.0 - std::sqrt(2.0 * s1 * s2 / (s1 * s1 + s2 * s2)) *
                   std::exp(-d * d / (4.0 * (s1 * s1 + s2 * s2)));
}

/// A run of `n` epochs at 10 Hz along a curve, with a diagonal covariance.
std::vector<EstimateRecord> MakeRun(int n) {
  std::vector<EstimateRecord> run;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    EstimateRecord r;
    r.state.t_ns = SecondsToNs(100.0 + 0.1 * i);
    r.state.p_w_b = Eigen::Vector3d(5.0 * i, 2.0 * std::sin(0.1 * i), 0.1 * g(rng));
    r.state.q_w_b =
        QuaternionFromRollPitchHeading(0.02 * g(rng), 0.02 * g(rng), (30.0 + i) * M_PI / 180.0);
    r.state.v_w = Eigen::Vector3d(5.0, 0.2, 0.0) + 0.1 * Eigen::Vector3d(g(rng), g(rng), 0);
    r.state.bg = 1e-4 * Eigen::Vector3d(g(rng), g(rng), g(rng));
    r.state.ba = 1e-2 * Eigen::Vector3d(g(rng), g(rng), g(rng));
    r.has_covariance = true;
    Eigen::Matrix<double, 15, 1> sd;
    sd << 0.01, 0.01, 0.02, 0.3, 0.4, 0.8, 0.05, 0.05, 0.1, 1e-4, 1e-4, 1e-4, 0.01, 0.01, 0.01;
    r.covariance = sd.array().square().matrix().asDiagonal();
    run.push_back(r);
  }
  return run;
}

TEST(RunFidelity, SameRunIsZeroEverywhere) {
  const std::vector<EstimateRecord> a = MakeRun(50);
  const FidelityResult r = CompareRuns(a, a);
  EXPECT_EQ(r.total, 50);
  EXPECT_EQ(r.both_valid, 50);
  EXPECT_EQ(r.share_one_valid, 0.0);
  for (int k = 0; k < kNumFidelityBlocks; ++k) {
    EXPECT_EQ(r.blocks[k].count, 50) << FidelityBlockName(static_cast<FidelityBlock>(k));
    EXPECT_EQ(r.blocks[k].ahed, 0.0) << FidelityBlockName(static_cast<FidelityBlock>(k));
    EXPECT_EQ(r.blocks[k].max_hed, 0.0);
  }
}

TEST(RunFidelity, PositionOffsetAndScaledCovarianceMatchTheClosedForm) {
  const std::vector<EstimateRecord> a = MakeRun(20);
  std::vector<EstimateRecord> b = a;
  for (EstimateRecord& r : b) {
    r.state.p_w_b.x() += 0.6;  // east only
    r.covariance.block<3, 3>(kPos, kPos) *= 4.0;
  }
  const FidelityResult res = CompareRuns(a, b);
  // East: d = 0.6, sigma 0.3 vs 0.6; north, up: d = 0, sigma x2. BC is the product.
  const double bc =
      (1 - Hed2OneD(0.6, 0.3, 0.6)) * (1 - Hed2OneD(0.0, 0.4, 0.8)) * (1 - Hed2OneD(0.0, 0.8, 1.6));
  for (const EpochFidelity& e : res.epochs) {
    const GaussianDistance& p = e.blocks[static_cast<int>(FidelityBlock::kPosition)];
    ASSERT_TRUE(p.valid);
    EXPECT_NEAR(p.hellinger_sq, 1.0 - bc, 1e-9);
    EXPECT_EQ(e.blocks[static_cast<int>(FidelityBlock::kHeading)].hellinger, 0.0);
    EXPECT_EQ(e.blocks[static_cast<int>(FidelityBlock::kVelocity)].hellinger, 0.0);
  }
  EXPECT_NEAR(res.blocks[static_cast<int>(FidelityBlock::kPosition)].ahed, std::sqrt(1.0 - bc),
              1e-9);
  EXPECT_GT(res.blocks[static_cast<int>(FidelityBlock::kFull)].ahed, 0.0);
}

TEST(RunFidelity, RotationAboutUpShowsInHeadingAndAttitude) {
  const std::vector<EstimateRecord> a = MakeRun(10);
  std::vector<EstimateRecord> b = a;
  const double yaw = 0.02;  // rad, counter-clockwise about up
  for (EstimateRecord& r : b) {
    r.state.q_w_b =
        Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())) * r.state.q_w_b;
  }
  const FidelityResult res = CompareRuns(a, b);
  // Heading: sigma 0.02 rad both; attitude: the same yaw on the up axis, others 0.
  const double expected = std::sqrt(Hed2OneD(yaw, 0.02, 0.02));
  for (const EpochFidelity& e : res.epochs) {
    EXPECT_NEAR(e.blocks[static_cast<int>(FidelityBlock::kHeading)].hellinger, expected, 1e-9);
    EXPECT_NEAR(e.blocks[static_cast<int>(FidelityBlock::kAttitude)].hellinger, expected, 1e-9);
    Eigen::VectorXd d;
    Eigen::MatrixXd pa, pb;
    BlockDifference(a[0], b[0], FidelityBlock::kAttitude, &d, &pa, &pb);
    EXPECT_NEAR(d(2), yaw, 1e-12);
    EXPECT_NEAR(d.head<2>().norm(), 0.0, 1e-12);
  }
}

TEST(RunFidelity, HeadingWrapsAround) {
  std::vector<EstimateRecord> a = MakeRun(1), b = MakeRun(1);
  a[0].state.q_w_b = QuaternionFromRollPitchHeading(0.0, 0.0, 359.5 * M_PI / 180.0);
  b[0].state.q_w_b = QuaternionFromRollPitchHeading(0.0, 0.0, 0.5 * M_PI / 180.0);
  Eigen::VectorXd d;
  Eigen::MatrixXd pa, pb;
  BlockDifference(a[0], b[0], FidelityBlock::kHeading, &d, &pa, &pb);
  EXPECT_NEAR(std::abs(d(0)), 1.0 * M_PI / 180.0, 1e-9);
}

TEST(RunFidelity, MissingAndInvalidEpochsCountAsOneValid) {
  const std::vector<EstimateRecord> a = MakeRun(40);
  std::vector<EstimateRecord> b;
  for (int i = 0; i < 40; ++i) {
    if (i < 10) continue;  // B starts late
    EstimateRecord r = a[i];
    r.state.t_ns += 200000;  // 0.2 ms later: still the same epoch
    if (i == 20) r.has_covariance = false;
    if (i == 21) r.covariance(3, 3) = -1.0;  // not a covariance
    b.push_back(r);
  }
  const FidelityResult res = CompareRuns(a, b);
  EXPECT_EQ(res.total, 40);
  EXPECT_EQ(res.only_a, 12);
  EXPECT_EQ(res.only_b, 0);
  EXPECT_EQ(res.both_valid, 28);
  EXPECT_NEAR(res.share_one_valid, 12.0 / 40.0, 1e-15);
  // Epoch 21: the full-state and position blocks are unusable, the others still count.
  EXPECT_EQ(res.blocks[static_cast<int>(FidelityBlock::kPosition)].count, 28);
  EXPECT_EQ(res.blocks[static_cast<int>(FidelityBlock::kHeading)].count, 29);
  EXPECT_EQ(res.blocks[static_cast<int>(FidelityBlock::kPosition)].ahed, 0.0);
  // With a tolerance below the 0.2 ms offset nothing matches.
  const FidelityResult strict = CompareRuns(a, b, 1e-4);
  EXPECT_EQ(strict.total, 70);
  EXPECT_EQ(strict.both_valid, 0);
}

TEST(RunFidelity, OrderOfRecordsDoesNotMatter) {
  const std::vector<EstimateRecord> a = MakeRun(30);
  std::vector<EstimateRecord> b = a;
  for (EstimateRecord& r : b) r.state.p_w_b.y() += 0.2;
  b.erase(b.begin() + 5);  // one epoch missing from B
  const FidelityResult sorted = CompareRuns(a, b);
  std::vector<EstimateRecord> a_shuffled = a, b_reversed(b.rbegin(), b.rend());
  std::shuffle(a_shuffled.begin(), a_shuffled.end(), std::mt19937_64(9));
  const FidelityResult shuffled = CompareRuns(a_shuffled, b_reversed);
  EXPECT_EQ(shuffled.total, 30);
  EXPECT_EQ(shuffled.both_valid, 29);
  EXPECT_EQ(shuffled.only_a, 1);
  ASSERT_EQ(shuffled.epochs.size(), sorted.epochs.size());
  for (size_t i = 0; i < sorted.epochs.size(); ++i) {
    EXPECT_EQ(shuffled.epochs[i].t_ns, sorted.epochs[i].t_ns);
  }
  for (int k = 0; k < kNumFidelityBlocks; ++k) {
    EXPECT_EQ(shuffled.blocks[k].ahed, sorted.blocks[k].ahed);
    EXPECT_EQ(shuffled.blocks[k].count, 29);
  }
  EXPECT_GT(sorted.blocks[static_cast<int>(FidelityBlock::kPosition)].ahed, 0.0);
}

// Two runs that differ by their noise only (each the truth plus an independent draw from the
// covariance both report) score the floor on every block (hellinger_floor.h): the per-block
// tangent spaces and dimensions of the fidelity code against the closed form.
TEST(RunFidelity, TwoConsistentRunsScoreTheFloorOnEveryBlock) {
  const std::vector<EstimateRecord> truth = MakeRun(3000);
  std::mt19937_64 rng(77);
  std::normal_distribution<double> g(0.0, 1.0);
  const auto draw = [&](const EstimateRecord& t) {
    EstimateRecord r = t;
    const Eigen::Matrix<double, 15, 1> sd = t.covariance.diagonal().cwiseSqrt();
    Eigen::Matrix<double, 15, 1> e;
    for (int i = 0; i < 15; ++i) e(i) = sd(i) * g(rng);
    r.state.q_w_b = (ExpQ<double>(e.segment<3>(kRot)) * t.state.q_w_b).normalized();
    r.state.p_w_b += e.segment<3>(kPos);
    r.state.v_w += e.segment<3>(kVel);
    r.state.bg += e.segment<3>(kBg);
    r.state.ba += e.segment<3>(kBa);
    return r;
  };
  std::vector<EstimateRecord> a, b;
  for (const EstimateRecord& t : truth) {
    a.push_back(draw(t));
    b.push_back(draw(t));
  }
  const FidelityResult r = CompareRuns(a, b);
  for (int k = 0; k < kNumFidelityBlocks; ++k) {
    const auto block = static_cast<FidelityBlock>(k);
    const HellingerFloor f = ConsistentRunsHellingerFloor(FidelityBlockDimension(block));
    EXPECT_NEAR(r.blocks[k].ahed, f.mean_hed, 4.0 * f.sd_hed / std::sqrt(3000.0))
        << FidelityBlockName(block);
  }
}

TEST(RunFidelity, RejectsANonsenseTolerance) {
  const std::vector<EstimateRecord> a = MakeRun(3);
  EXPECT_THROW(CompareRuns(a, a, -1e-3), std::invalid_argument);
  EXPECT_THROW(CompareRuns(a, a, std::nan("")), std::invalid_argument);
  EXPECT_THROW(CompareRuns(a, a, 1e9), std::invalid_argument);
  EXPECT_EQ(CompareRuns(a, a, 0.0).total, 6);  // zero tolerance: nothing is the same epoch
}

}  // namespace
}  // namespace skerry
