#include "skerry/eval/run_fidelity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>

#include "skerry/core/heading.h"
#include "skerry/core/so3.h"
#include "skerry/io/atomic_file.h"

namespace skerry {

namespace {

struct BlockLayout {
  int start;  ///< in the 15-D tangent (nav_state.h); -1 for heading
  int size;
};

BlockLayout Layout(FidelityBlock block) {
  switch (block) {
    case FidelityBlock::kPosition:
      return {kPos, 3};
    case FidelityBlock::kHeading:
      return {-1, 1};
    case FidelityBlock::kAttitude:
      return {kRot, 3};
    case FidelityBlock::kVelocity:
      return {kVel, 3};
    case FidelityBlock::kBiases:
      return {kBg, 6};
    case FidelityBlock::kFull:
      return {0, kStateDim};
  }
  return {0, 0};
}

/// The full 15-D difference B - A: [dtheta (world), dp, dv, dbg, dba].
Eigen::Matrix<double, 15, 1> FullDifference(const NavState& a, const NavState& b) {
  Eigen::Matrix<double, 15, 1> d;
  const Eigen::Quaterniond dq = b.q_w_b.normalized() * a.q_w_b.normalized().conjugate();
  d.segment<3>(kRot) = LogQ(dq);
  d.segment<3>(kPos) = b.p_w_b - a.p_w_b;
  d.segment<3>(kVel) = b.v_w - a.v_w;
  d.segment<3>(kBg) = b.bg - a.bg;
  d.segment<3>(kBa) = b.ba - a.ba;
  return d;
}

std::vector<const EstimateRecord*> SortedByTime(const std::vector<EstimateRecord>& run) {
  std::vector<const EstimateRecord*> sorted;
  sorted.reserve(run.size());
  for (const EstimateRecord& r : run) sorted.push_back(&r);
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto* x, const auto* y) { return x->state.t_ns < y->state.t_ns; });
  return sorted;
}

bool StateFinite(const NavState& s) {
  return s.q_w_b.coeffs().allFinite() && s.p_w_b.allFinite() && s.v_w.allFinite() &&
         s.bg.allFinite() && s.ba.allFinite();
}

}  // namespace

int FidelityBlockDimension(FidelityBlock block) {
  switch (block) {
    case FidelityBlock::kPosition:
    case FidelityBlock::kAttitude:
    case FidelityBlock::kVelocity:
      return 3;
    case FidelityBlock::kHeading:
      return 1;
    case FidelityBlock::kBiases:
      return 6;
    case FidelityBlock::kFull:
      return kStateDim;
  }
  return 0;
}

const char* FidelityBlockName(FidelityBlock block) {
  switch (block) {
    case FidelityBlock::kPosition:
      return "position";
    case FidelityBlock::kHeading:
      return "heading";
    case FidelityBlock::kAttitude:
      return "attitude";
    case FidelityBlock::kVelocity:
      return "velocity";
    case FidelityBlock::kBiases:
      return "biases";
    case FidelityBlock::kFull:
      return "full";
  }
  return "?";
}

void BlockDifference(const EstimateRecord& a,
                     const EstimateRecord& b,
                     FidelityBlock block,
                     Eigen::VectorXd* delta,
                     Eigen::MatrixXd* p_a,
                     Eigen::MatrixXd* p_b) {
  const BlockLayout l = Layout(block);
  if (block == FidelityBlock::kHeading) {
    // Heading is clockwise from north, the rotation about up counter-clockwise: negate so that
    // Delta has the sign of the up component of the attitude Delta. The wrap matters.
    const double dh = WrapAngle(HeadingRad(b.state.q_w_b) - HeadingRad(a.state.q_w_b));
    *delta = Eigen::VectorXd::Constant(1, -dh);
    *p_a = a.covariance.block<1, 1>(kRot + 2, kRot + 2);
    *p_b = b.covariance.block<1, 1>(kRot + 2, kRot + 2);
    return;
  }
  *delta = FullDifference(a.state, b.state).segment(l.start, l.size);
  *p_a = a.covariance.block(l.start, l.start, l.size, l.size);
  *p_b = b.covariance.block(l.start, l.start, l.size, l.size);
}

bool IsValidEstimate(const EstimateRecord& record) {
  return record.has_covariance && StateFinite(record.state) && IsCovariance(record.covariance);
}

FidelityResult CompareRuns(const std::vector<EstimateRecord>& a,
                           const std::vector<EstimateRecord>& b,
                           double tolerance_s) {
  // From the CLI (--tolerance): a NaN would make llround undefined, a negative value matches
  // nothing, and an hour's tolerance would match keyframes of different times.
  if (!(tolerance_s >= 0.0 && tolerance_s <= 3600.0)) {
    throw std::invalid_argument("CompareRuns: tolerance_s must be in [0, 3600] s, got " +
                                std::to_string(tolerance_s));
  }
  FidelityResult result;
  const TimeNs tol = static_cast<TimeNs>(std::llround(tolerance_s * 1e9));
  auto usable = [](const EstimateRecord& r) { return r.has_covariance && StateFinite(r.state); };
  // The merge below walks both runs in time order; states.csv is written in time order, but a
  // run edited or concatenated by hand may not be, so sort views rather than trust the input.
  const std::vector<const EstimateRecord*> sa = SortedByTime(a), sb = SortedByTime(b);
  size_t i = 0, j = 0;
  std::array<double, kNumFidelityBlocks> sum_hed{}, sum_cov{}, sum_mean{}, sum_bhatt{};
  while (i < sa.size() || j < sb.size()) {
    const EstimateRecord* ra = nullptr;
    const EstimateRecord* rb = nullptr;
    if (i < sa.size() && j < sb.size() && std::llabs(sa[i]->state.t_ns - sb[j]->state.t_ns) < tol) {
      ra = sa[i++];
      rb = sb[j++];
    } else if (j >= sb.size() || (i < sa.size() && sa[i]->state.t_ns < sb[j]->state.t_ns)) {
      ra = sa[i++];
    } else {
      rb = sb[j++];
    }
    EpochFidelity e;
    e.t_ns = ra ? ra->state.t_ns : rb->state.t_ns;
    e.valid_a = ra && IsValidEstimate(*ra);
    e.valid_b = rb && IsValidEstimate(*rb);
    if (ra && rb && usable(*ra) && usable(*rb)) {
      for (int k = 0; k < kNumFidelityBlocks; ++k) {
        Eigen::VectorXd delta;
        Eigen::MatrixXd pa, pb;
        BlockDifference(*ra, *rb, static_cast<FidelityBlock>(k), &delta, &pa, &pb);
        e.blocks[k] = CompareGaussians(delta, pa, pb);
        if (!e.blocks[k].valid) continue;
        FidelityBlockSummary& s = result.blocks[k];
        ++s.count;
        sum_hed[k] += e.blocks[k].hellinger;
        sum_cov[k] += e.blocks[k].covdiff;
        sum_mean[k] += e.blocks[k].meandiff;
        sum_bhatt[k] += e.blocks[k].bhattacharyya;
        s.max_hed = std::max(s.max_hed, e.blocks[k].hellinger);
      }
    }
    ++result.total;
    if (e.valid_a && e.valid_b) ++result.both_valid;
    if (e.valid_a && !e.valid_b) ++result.only_a;
    if (e.valid_b && !e.valid_a) ++result.only_b;
    result.epochs.push_back(e);
  }
  for (int k = 0; k < kNumFidelityBlocks; ++k) {
    FidelityBlockSummary& s = result.blocks[k];
    if (s.count == 0) continue;
    s.ahed = sum_hed[k] / s.count;
    s.mean_covdiff = sum_cov[k] / s.count;
    s.mean_meandiff = sum_mean[k] / s.count;
    s.mean_bhattacharyya = sum_bhatt[k] / s.count;
  }
  result.share_one_valid =
      result.total > 0 ? static_cast<double>(result.only_a + result.only_b) / result.total : 0.0;
  return result;
}

std::vector<std::string> FidelityCsvColumns() {
  std::vector<std::string> columns = {"t", "valid_a", "valid_b"};
  for (const char* kind : {"hed", "covdiff", "bhatt"}) {
    for (int k = 0; k < kNumFidelityBlocks; ++k) {
      columns.push_back(std::string(kind) + "_" + FidelityBlockName(static_cast<FidelityBlock>(k)));
    }
  }
  return columns;
}

void WriteFidelityCsv(const std::string& path, const FidelityResult& result) {
  AtomicFile file(path);
  std::ofstream& f = file.stream();
  const std::vector<std::string> columns = FidelityCsvColumns();
  for (size_t c = 0; c < columns.size(); ++c) f << (c ? "," : "") << columns[c];
  f << "\n";
  char buf[64];
  for (const EpochFidelity& e : result.epochs) {
    std::snprintf(buf, sizeof(buf), "%.9f,%d,%d", NsToSeconds(e.t_ns), e.valid_a ? 1 : 0,
                  e.valid_b ? 1 : 0);
    f << buf;
    for (int kind = 0; kind < 3; ++kind) {
      for (int k = 0; k < kNumFidelityBlocks; ++k) {
        const GaussianDistance& d = e.blocks[k];
        f << ",";
        if (!d.valid) continue;
        const double v = kind == 0 ? d.hellinger : kind == 1 ? d.covdiff : d.bhattacharyya;
        std::snprintf(buf, sizeof(buf), "%.9g", v);
        f << buf;
      }
    }
    f << "\n";
  }
  file.Commit();
}

}  // namespace skerry
