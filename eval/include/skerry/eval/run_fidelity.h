#pragma once
/// \file
/// The fidelity of two estimator runs (two configurations, or real vs simulated data of one
/// scenario): per-epoch Hellinger distance between their Gaussian state estimates, per state
/// block, and its averages (AHED). Definitions and conventions: docs/fidelity.md.

#include <array>
#include <string>
#include <vector>

#include "skerry/eval/gaussian_distance.h"
#include "skerry/io/estimate_io.h"

namespace skerry {

/// The blocks of the 15-D state the distance is taken on. The full state saturates (HED -> 1
/// as soon as any one block differs by a few sigma), so the blocks say which part differs.
enum class FidelityBlock : int {
  kPosition = 0,  ///< 3: ENU position
  kHeading,       ///< 1: rotation about world up (the up component of the attitude error)
  kAttitude,      ///< 3: rotation, world-frame (left) tangent
  kVelocity,      ///< 3
  kBiases,        ///< 6: gyro and accelerometer biases
  kFull,          ///< 15: everything
};
constexpr int kNumFidelityBlocks = 6;

/// "position", "heading", "attitude", "velocity", "biases", "full".
const char* FidelityBlockName(FidelityBlock block);
/// The block's dimension: 3, 1, 3, 3, 6, 15 (its floor: hellinger_floor.h).
int FidelityBlockDimension(FidelityBlock block);

struct EpochFidelity {
  TimeNs t_ns = 0;
  bool valid_a = false;  ///< run A has a record here with a usable covariance
  bool valid_b = false;
  std::array<GaussianDistance, kNumFidelityBlocks> blocks{};  ///< set when both are valid
};

struct FidelityBlockSummary {
  int count = 0;      ///< epochs where both runs are valid for this block
  double ahed = 0.0;  ///< mean HED over them
  double max_hed = 0.0;
  double mean_covdiff = 0.0;        ///< mean covariance-only HED
  double mean_meandiff = 0.0;       ///< mean mean-only HED (gaussian_distance.h)
  double mean_bhattacharyya = 0.0;  ///< mean Bhattacharyya distance
};

struct FidelityResult {
  std::vector<EpochFidelity> epochs;  ///< the union of both runs' epochs, in time order
  std::array<FidelityBlockSummary, kNumFidelityBlocks> blocks{};
  int total = 0;                 ///< epochs
  int both_valid = 0;            ///< with the full state valid in both runs
  int only_a = 0;                ///< valid in A only
  int only_b = 0;                ///< valid in B only
  double share_one_valid = 0.0;  ///< (only_a + only_b) / total
};

/// The mean difference and covariances of one block, B relative to A, in the tangent space of
/// skerry's covariances (nav_state.h: world-frame rotation perturbation). Attitude:
/// dtheta = Log(R_b R_a^T), the world-frame form of the Log(R_a^T R_b) of the literature
/// (rotated by R_a). Heading: the wrapped difference of headings (rotation about up), whose
/// variance is the up-up entry of the rotation block.
void BlockDifference(const EstimateRecord& a,
                     const EstimateRecord& b,
                     FidelityBlock block,
                     Eigen::VectorXd* delta,
                     Eigen::MatrixXd* p_a,
                     Eigen::MatrixXd* p_b);

/// A record that is a valid estimate: a finite state and a covariance that is finite, symmetric
/// and positive definite. The one definition of a valid epoch (fidelity, compare's share_valid).
bool IsValidEstimate(const EstimateRecord& record);

/// Matches epochs of A and B whose times differ by less than `tolerance_s` and computes the
/// distances. Records without a covariance, or with one that is not positive definite for a
/// block, are not valid (for that block). The runs need not be sorted by time. Throws
/// std::invalid_argument unless 0 <= tolerance_s <= 3600.
FidelityResult CompareRuns(const std::vector<EstimateRecord>& a,
                           const std::vector<EstimateRecord>& b,
                           double tolerance_s = 1e-3);

/// Per-epoch CSV: t,valid_a,valid_b,hed_<block>...,covdiff_<block>...,bhatt_<block>... with
/// empty cells where the block is not valid in both runs.
void WriteFidelityCsv(const std::string& path, const FidelityResult& result);

/// The header of that CSV, column by column.
std::vector<std::string> FidelityCsvColumns();

}  // namespace skerry
