#include "skerry/twin/twin_fidelity.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "skerry/eval/hellinger_floor.h"

namespace skerry {

TwinFidelity CompareWithTwins(const std::vector<EstimateRecord>& real,
                              const std::vector<std::vector<EstimateRecord>>& twins,
                              double alpha,
                              double tolerance_s) {
  if (twins.size() < 2) throw std::invalid_argument("CompareWithTwins: needs at least 2 twins");
  if (!(alpha > 0.0 && alpha < 1.0)) {
    throw std::invalid_argument("CompareWithTwins: alpha must be in (0, 1)");
  }
  const size_t n = twins.size() + 1;
  auto run = [&](size_t i) -> const std::vector<EstimateRecord>& {
    return i == 0 ? real : twins[i - 1];
  };
  TwinFidelity out;
  out.twins = static_cast<int>(twins.size());
  out.alpha = alpha;
  std::array<std::vector<std::vector<double>>, kNumFidelityBlocks> meandiff, covdiff, epochs;
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    out.ahed[b].assign(n, std::vector<double>(n, 0.0));
    meandiff[b] = covdiff[b] = epochs[b] = out.ahed[b];
  }
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      const FidelityResult r = CompareRuns(run(i), run(j), tolerance_s);
      for (int b = 0; b < kNumFidelityBlocks; ++b) {
        const FidelityBlockSummary& s = r.blocks[b];
        out.ahed[b][i][j] = out.ahed[b][j][i] = s.ahed;
        meandiff[b][i][j] = meandiff[b][j][i] = s.mean_meandiff;
        covdiff[b][i][j] = covdiff[b][j][i] = s.mean_covdiff;
        epochs[b][i][j] = epochs[b][j][i] = s.count;
      }
    }
  }
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    TwinFidelityBlock& f = out.blocks[b];
    const auto& A = out.ahed[b];
    f.floor = ConsistentRunsHellingerFloor(FidelityBlockDimension(static_cast<FidelityBlock>(b)))
                  .mean_hed;
    double epochs_sum = 0.0;
    for (size_t j = 1; j < n; ++j) {
      f.real_ahed += A[0][j] / (n - 1);
      f.real_meandiff += meandiff[b][0][j] / (n - 1);
      f.real_covdiff += covdiff[b][0][j] / (n - 1);
      epochs_sum += epochs[b][0][j];
    }
    f.epochs = static_cast<int>(std::lround(epochs_sum / (n - 1)));
    std::vector<double> pairs;
    double md = 0.0, cd = 0.0;
    for (size_t i = 1; i < n; ++i) {
      for (size_t j = i + 1; j < n; ++j) {
        pairs.push_back(A[i][j]);
        md += meandiff[b][i][j];
        cd += covdiff[b][i][j];
      }
    }
    const double np = static_cast<double>(pairs.size());
    for (double v : pairs) f.twins_ahed += v / np;
    for (double v : pairs) f.twins_sd += (v - f.twins_ahed) * (v - f.twins_ahed);
    f.twins_sd = pairs.size() > 1 ? std::sqrt(f.twins_sd / (np - 1.0)) : 0.0;
    f.twins_max = *std::max_element(pairs.begin(), pairs.end());
    f.twins_meandiff = md / np;
    f.twins_covdiff = cd / np;
    // D_m: each run's mean distance to all the others; the recording's rank among them.
    std::vector<double> D(n, 0.0);
    for (size_t i = 0; i < n; ++i) {
      for (size_t j = 0; j < n; ++j) {
        if (i != j) D[i] += A[i][j] / (n - 1);
      }
    }
    int hi = 0, lo = 0;
    for (size_t m = 0; m < n; ++m) {
      hi += D[m] >= D[0] ? 1 : 0;
      lo += D[m] <= D[0] ? 1 : 0;
    }
    f.p_value = std::min(1.0, 2.0 * std::min(hi, lo) / static_cast<double>(n));
    f.indistinguishable = f.p_value > alpha;
    double mean_d = 0.0, var_d = 0.0;
    for (size_t m = 1; m < n; ++m) mean_d += D[m] / (n - 1);
    for (size_t m = 1; m < n; ++m) var_d += (D[m] - mean_d) * (D[m] - mean_d) / (n - 2);
    f.z = var_d > 0.0 ? (D[0] - mean_d) / std::sqrt(var_d) : 0.0;
  }
  return out;
}

}  // namespace skerry
