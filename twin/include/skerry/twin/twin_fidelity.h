#pragma once
/// \file
/// Is a twin indistinguishable from its recording? The Hellinger distance between the
/// estimator's outputs on the recording and on twins of several seeds, per state block, against
/// the spread of the same distance between the twins themselves (docs/twin.md).
///
/// The test is a two-sided rank (permutation) test. Take the recording and K twins as K + 1
/// runs; for each run m, D_m is the mean AHED between m and every other run. If the recording
/// were one more twin, the K + 1 runs would be exchangeable and the rank of D_recording among all
/// D_m uniform, so with r_hi = #{m : D_m >= D_recording} and r_lo = #{m : D_m <= D_recording},
/// p = min(1, 2 min(r_hi, r_lo) / (K + 1)) is a valid p-value (ties counted against the twin),
/// and the twin is rejected, for that block, when p <= alpha. Both sides matter: a twin whose
/// noise is too small leaves the recording the run farthest from all others, one whose noise is
/// too large leaves it the closest (the twins scatter more among themselves than about the
/// recording). With K = 19 and alpha = 0.1 a block is rejected when the recording is the
/// farthest or the closest of the 20 runs. The test uses no distribution of AHED, only the
/// exchangeability of runs that differ by their noise; `z` (the recording's D against the mean
/// and standard deviation of the twins' D) says how far out it lies.

#include <array>
#include <string>
#include <vector>

#include "skerry/eval/run_fidelity.h"
#include "skerry/io/estimate_io.h"

namespace skerry {

struct TwinFidelityBlock {
  int epochs = 0;              ///< mean over the recording-vs-twin comparisons
  double real_ahed = 0.0;      ///< mean AHED of the recording against each twin
  double real_meandiff = 0.0;  ///< its mean-only and covariance-only parts
  double real_covdiff = 0.0;
  double twins_ahed = 0.0;  ///< mean AHED over the pairs of twins
  double twins_sd = 0.0;    ///< their standard deviation
  double twins_max = 0.0;
  double twins_meandiff = 0.0;
  double twins_covdiff = 0.0;
  double floor = 0.0;    ///< the closed form for a consistent estimator (hellinger_floor.h)
  double p_value = 1.0;  ///< of the rank test above
  double z = 0.0;        ///< (D_recording - mean D_twin) / sd D_twin
  bool indistinguishable = true;  ///< p > alpha
};

struct TwinFidelity {
  int twins = 0;
  int failed_twins = 0;  ///< twins run but left out: the estimator gave up on them (set by callers)
  double alpha = 0.1;
  std::array<TwinFidelityBlock, kNumFidelityBlocks> blocks{};
  /// Every AHED, runs in the order recording, twin 1..K: ahed[b][i][j] (symmetric, zero
  /// diagonal).
  std::array<std::vector<std::vector<double>>, kNumFidelityBlocks> ahed;
  /// Over time: at each of the recording's epochs, the mean HED per block against the twins
  /// valid there (NaN where none is), and how many twins were.
  std::vector<TimeNs> t_ns;
  std::array<std::vector<double>, kNumFidelityBlocks> hed_over_time;
  std::vector<int> twins_valid;
  /// Coverage: the share of the recording's epochs at which both it and a twin have a valid
  /// estimate, averaged over the twins (the rest is where one run had none: before it started,
  /// or a covariance that was not positive definite).
  double coverage = 0.0;
};

/// fidelity_over_time.csv: t (s), twins_valid, then hed_<block> for every block (empty where no
/// twin is valid).
void WriteFidelityOverTimeCsv(const std::string& path, const TwinFidelity& fidelity);

/// The two-sided rank p-value of one value among `runs` exchangeable ones (itself included):
/// min(1, 2 min(at_least, at_most) / runs), with at_least / at_most the runs whose value is >= / <=
/// it (itself counted in both, ties against it).
double TwoSidedRankP(int at_least, int at_most, int runs);

/// The distances and the test; `twins` holds at least 2 runs. Throws std::invalid_argument
/// otherwise or unless 0 < alpha < 1.
TwinFidelity CompareWithTwins(const std::vector<EstimateRecord>& real,
                              const std::vector<std::vector<EstimateRecord>>& twins,
                              double alpha = 0.1,
                              double tolerance_s = 1e-3);

}  // namespace skerry
