#include "skerry/twin/twin_fidelity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "skerry/core/time.h"
#include "skerry/eval/hellinger_floor.h"
#include "skerry/io/atomic_file.h"
#include "skerry/io/csv_reader.h"

namespace skerry {

double TwoSidedRankP(int at_least, int at_most, int runs) {
  return std::min(1.0, 2.0 * std::min(at_least, at_most) / static_cast<double>(runs));
}

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
  // Over time, at the recording's epochs (sorted), from its comparisons with each twin.
  std::vector<TimeNs> times;
  for (const EstimateRecord& r : real) times.push_back(r.state.t_ns);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  out.t_ns = times;
  out.twins_valid.assign(times.size(), 0);
  std::array<std::vector<double>, kNumFidelityBlocks> sum;
  std::array<std::vector<int>, kNumFidelityBlocks> count;
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    sum[b].assign(times.size(), 0.0);
    count[b].assign(times.size(), 0);
  }
  double covered = 0.0;
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      const FidelityResult r = CompareRuns(run(i), run(j), tolerance_s);
      if (i == 0) {
        int both = 0;
        for (const EpochFidelity& e : r.epochs) {
          const auto it =
              std::lower_bound(times.begin(), times.end(), e.t_ns - SecondsToNs(tolerance_s));
          if (it == times.end() || std::abs(*it - e.t_ns) > SecondsToNs(tolerance_s)) continue;
          const size_t k = static_cast<size_t>(it - times.begin());
          if (!(e.valid_a && e.valid_b)) continue;
          ++both;
          ++out.twins_valid[k];
          for (int b = 0; b < kNumFidelityBlocks; ++b) {
            if (!e.blocks[b].valid) continue;
            sum[b][k] += e.blocks[b].hellinger;
            ++count[b][k];
          }
        }
        covered += times.empty() ? 0.0 : static_cast<double>(both) / times.size();
      }
      for (int b = 0; b < kNumFidelityBlocks; ++b) {
        const FidelityBlockSummary& s = r.blocks[b];
        out.ahed[b][i][j] = out.ahed[b][j][i] = s.ahed;
        meandiff[b][i][j] = meandiff[b][j][i] = s.mean_meandiff;
        covdiff[b][i][j] = covdiff[b][j][i] = s.mean_covdiff;
        epochs[b][i][j] = epochs[b][j][i] = s.count;
      }
    }
  }
  out.coverage = covered / static_cast<double>(n - 1);
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    out.hed_over_time[b].resize(times.size());
    for (size_t k = 0; k < times.size(); ++k) {
      out.hed_over_time[b][k] =
          count[b][k] > 0 ? sum[b][k] / count[b][k] : std::numeric_limits<double>::quiet_NaN();
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
    f.p_value = TwoSidedRankP(hi, lo, static_cast<int>(n));
    f.indistinguishable = f.p_value > alpha;
    double mean_d = 0.0, var_d = 0.0;
    for (size_t m = 1; m < n; ++m) mean_d += D[m] / (n - 1);
    for (size_t m = 1; m < n; ++m) var_d += (D[m] - mean_d) * (D[m] - mean_d) / (n - 2);
    f.z = var_d > 0.0 ? (D[0] - mean_d) / std::sqrt(var_d) : 0.0;
  }
  return out;
}

void WriteFidelityOverTimeCsv(const std::string& path, const TwinFidelity& f) {
  AtomicFile file(path);
  std::ofstream& out = file.stream();
  out << "t,twins_valid";
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    out << ",hed_" << FidelityBlockName(static_cast<FidelityBlock>(b));
  }
  out << '\n';
  char cell[32];
  for (size_t k = 0; k < f.t_ns.size(); ++k) {
    out << FormatSeconds(f.t_ns[k]) << ',' << f.twins_valid[k];
    for (int b = 0; b < kNumFidelityBlocks; ++b) {
      out << ',';
      const double v = f.hed_over_time[b][k];
      if (std::isfinite(v)) {
        std::snprintf(cell, sizeof(cell), "%.4f", v);
        out << cell;
      }
    }
    out << '\n';
  }
  file.Commit();
}

}  // namespace skerry
