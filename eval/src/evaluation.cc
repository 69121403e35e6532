#include "skerry/eval/evaluation.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "skerry/core/chi_square.h"
#include "skerry/core/heading.h"
#include "skerry/core/mahalanobis.h"
#include "skerry/core/so3.h"

namespace skerry {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// Stats of signed values: rmse/mean/median as usual, max of |value|.
Stats SignedStats(const std::vector<double>& values) {
  Stats stats = ComputeStats(values);
  stats.max = 0.0;
  for (double v : values) stats.max = std::max(stats.max, std::fabs(v));
  return stats;
}

}  // namespace

double Percentile(std::vector<double> values, double p) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(rank));
  const size_t hi = std::min(lo + 1, values.size() - 1);
  const double frac = rank - static_cast<double>(lo);
  return values[lo] + frac * (values[hi] - values[lo]);
}

Stats ComputeStats(std::vector<double> values) {
  Stats stats;
  stats.count = static_cast<int>(values.size());
  if (values.empty()) return stats;
  double sum = 0.0;
  double sum_sq = 0.0;
  stats.max = values.front();
  for (double v : values) {
    sum += v;
    sum_sq += v * v;
    stats.max = std::max(stats.max, v);
  }
  const double n = static_cast<double>(values.size());
  stats.mean = sum / n;
  stats.rmse = std::sqrt(sum_sq / n);
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  stats.median = values[mid];
  if (values.size() % 2 == 0) {
    const double lower = *std::max_element(values.begin(), values.begin() + mid);
    stats.median = 0.5 * (stats.median + lower);
  }
  return stats;
}

EvaluationResult Evaluate(const std::vector<EstimateRecord>& estimate,
                          const std::vector<StampedPose>& groundtruth,
                          double rpe_delta_s) {
  EvaluationResult result;
  result.rpe_delta_s = rpe_delta_s;
  std::vector<double> horizontal, vertical, position3d, east, north, up, heading, tilt;
  std::vector<double> nees_pos, nees_pose;
  // Matched truth per estimate epoch (for RPE); `matched[k]` false outside the truth span.
  std::vector<StampedPose> truth_at(estimate.size());
  std::vector<bool> matched(estimate.size(), false);

  for (std::size_t k = 0; k < estimate.size(); ++k) {
    const EstimateRecord& record = estimate[k];
    const NavState& est = record.state;
    StampedPose truth;
    if (!InterpolatePose(groundtruth, est.t_ns, &truth)) {
      ++result.unmatched;
      continue;
    }
    matched[k] = true;
    truth_at[k] = truth;

    EpochError e;
    e.t_ns = est.t_ns;
    e.p_err_w = est.p_w_b - truth.p_w_b;
    // World-frame (left) rotation error: R_est = Exp(rot_err) R_true, the same tangent as the
    // covariance's rotation block.
    e.rot_err_w = LogQ(Eigen::Quaterniond(est.q_w_b * truth.q_w_b.conjugate()));
    double dh = HeadingDeg(est.q_w_b) - HeadingDeg(truth.q_w_b);
    dh = std::remainder(dh, 360.0);  // [-180, 180]
    if (dh <= -180.0) dh += 360.0;   // the range is (-180, 180]
    e.heading_err_deg = dh;

    if (record.has_covariance) {
      const Eigen::Matrix3d P_pp = record.covariance.block<3, 3>(kPos, kPos);
      Eigen::Matrix<double, 6, 1> x;
      x << e.rot_err_w, e.p_err_w;
      const Eigen::Matrix<double, 6, 6> P_pose = record.covariance.block<6, 6>(kRot, kRot);
      const Eigen::Vector3d dp = e.p_err_w;
      const std::optional<double> pos = SquaredMahalanobis<3>(dp, P_pp);
      const std::optional<double> pose = SquaredMahalanobis<6>(x, P_pose);
      const std::optional<double> hor = SquaredMahalanobis<2>(
          Eigen::Vector2d(dp.head<2>()), Eigen::Matrix2d(P_pp.topLeftCorner<2, 2>()));
      e.has_nees = pos && pose && hor;
      if (e.has_nees) {
        e.nees_pos = *pos;
        e.nees_pose = *pose;
        e.nees_horizontal = *hor;
        nees_pos.push_back(e.nees_pos);
        nees_pose.push_back(e.nees_pose);
      }
    }

    horizontal.push_back(e.p_err_w.head<2>().norm());
    vertical.push_back(std::fabs(e.p_err_w.z()));
    position3d.push_back(e.p_err_w.norm());
    east.push_back(e.p_err_w.x());
    north.push_back(e.p_err_w.y());
    up.push_back(e.p_err_w.z());
    heading.push_back(std::fabs(e.heading_err_deg));
    tilt.push_back(e.rot_err_w.head<2>().norm() * kRadToDeg);
    result.epochs.push_back(e);
  }

  result.horizontal = ComputeStats(horizontal);
  result.vertical = ComputeStats(vertical);
  result.position3d = ComputeStats(position3d);
  result.east = SignedStats(east);
  result.north = SignedStats(north);
  result.up = SignedStats(up);
  result.heading_deg = ComputeStats(heading);
  result.roll_pitch_deg = ComputeStats(tilt);

  result.nees_count = static_cast<int>(nees_pos.size());
  if (result.nees_count > 0) {
    result.anees_pos = ComputeStats(nees_pos).mean;
    result.anees_pose = ComputeStats(nees_pose).mean;
    result.nees_effective_count = EffectiveSampleSize(nees_pos);
  }

  // Relative pose error: for each matched epoch i, the first estimate epoch j at or after
  // t_i + delta (accepted if no later than t_i + 1.5 delta, so gaps do not stretch the interval).
  // E = (T_true_i^-1 T_true_j)^-1 (T_est_i^-1 T_est_j).
  std::vector<double> rpe_trans, rpe_rot;
  const TimeNs delta_ns = SecondsToNs(rpe_delta_s);
  if (delta_ns > 0) {
    std::size_t j = 0;
    for (std::size_t i = 0; i < estimate.size(); ++i) {
      if (!matched[i]) continue;
      const TimeNs target = estimate[i].state.t_ns + delta_ns;
      j = std::max(j, i + 1);
      while (j < estimate.size() && estimate[j].state.t_ns < target) ++j;
      if (j >= estimate.size()) break;
      if (!matched[j] || estimate[j].state.t_ns > target + delta_ns / 2) continue;
      const NavState& ei = estimate[i].state;
      const NavState& ej = estimate[j].state;
      const StampedPose& ti = truth_at[i];
      const StampedPose& tj = truth_at[j];
      const Eigen::Quaterniond q_est = ei.q_w_b.conjugate() * ej.q_w_b;
      const Eigen::Vector3d p_est = ei.q_w_b.conjugate() * (ej.p_w_b - ei.p_w_b);
      const Eigen::Quaterniond q_true = ti.q_w_b.conjugate() * tj.q_w_b;
      const Eigen::Vector3d p_true = ti.q_w_b.conjugate() * (tj.p_w_b - ti.p_w_b);
      // E = T_true^-1 T_est: rotation q_true^-1 q_est, translation q_true^-1 (p_est - p_true).
      const Eigen::Quaterniond q_err = q_true.conjugate() * q_est;
      const Eigen::Vector3d p_err = q_true.conjugate() * (p_est - p_true);
      rpe_trans.push_back(p_err.norm());
      rpe_rot.push_back(LogQ(q_err).norm() * kRadToDeg);
    }
  }
  result.rpe_trans_m = ComputeStats(rpe_trans);
  result.rpe_rot_deg = ComputeStats(rpe_rot);
  return result;
}

std::pair<double, double> AneesBounds(int dof, double count, double p) {
  if (!(count > 0.0) || dof <= 0) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan};  // no samples: no bounds (callers print n/a)
  }
  const double n = count;
  const double total_dof = static_cast<double>(dof) * n;
  return {ChiSquareQuantile((1.0 - p) / 2.0, total_dof) / n,
          ChiSquareQuantile((1.0 + p) / 2.0, total_dof) / n};
}

double EffectiveSampleSize(const std::vector<double>& x) {
  const size_t n = x.size();
  if (n < 3) return static_cast<double>(n);
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(n);
  // Centred once; each lag is then one vectorised dot product (an hour's NEES at 10 Hz is
  // worth ~10 epochs, so the sequence below runs to lags of ~1800 over 36000 samples).
  const Eigen::ArrayXd y =
      Eigen::Map<const Eigen::ArrayXd>(x.data(), static_cast<Eigen::Index>(n)) - mean;
  auto autocovariance = [&](size_t lag) {
    const Eigen::Index m = static_cast<Eigen::Index>(n - lag);
    return y.head(m).matrix().dot(y.tail(m).matrix()) / static_cast<double>(n);
  };
  const double c0 = autocovariance(0);
  if (!(c0 > 0.0)) return static_cast<double>(n);
  // Geyer's initial positive (and monotone) sequence of Gamma_m = c_2m + c_2m+1.
  double sum_gamma = 0.0, previous = std::numeric_limits<double>::infinity();
  for (size_t m = 0; 2 * m + 1 < n / 2; ++m) {
    double gamma = (m == 0 ? c0 : autocovariance(2 * m)) + autocovariance(2 * m + 1);
    if (gamma <= 0.0) break;
    gamma = std::min(gamma, previous);
    sum_gamma += gamma;
    previous = gamma;
  }
  const double tau = std::max(1.0, (2.0 * sum_gamma - c0) / c0);
  return std::clamp(static_cast<double>(n) / tau, 1.0, static_cast<double>(n));
}

NeesTest MonteCarloNeesTest(const std::vector<const EvaluationResult*>& runs,
                            int min_runs,
                            double p,
                            TimeNs bin_ns,
                            bool horizontal) {
  std::map<TimeNs, std::pair<double, int>> by_epoch;  // sum of NEES, runs
  for (const EvaluationResult* run : runs) {
    std::map<TimeNs, bool> seen;  // one epoch per run per bin
    for (const EpochError& e : run->epochs) {
      if (!e.has_nees) continue;
      const TimeNs key = bin_ns > 0 ? (e.t_ns + bin_ns / 2) / bin_ns * bin_ns : e.t_ns;
      if (seen[key]) continue;
      seen[key] = true;
      auto& [sum, count] = by_epoch[key];
      sum += horizontal ? e.nees_horizontal : e.nees_pos;
      ++count;
    }
  }
  NeesTest test;
  std::map<int, std::pair<double, double>> bounds;  // by number of runs
  int inside = 0, above = 0, below = 0;
  double sum = 0.0;
  for (const auto& [t, acc] : by_epoch) {
    if (acc.second < min_runs) continue;
    auto it = bounds.find(acc.second);
    if (it == bounds.end()) {
      it = bounds.emplace(acc.second, AneesBounds(horizontal ? 2 : 3, acc.second, p)).first;
    }
    const double mean = acc.first / acc.second;
    ++test.epochs;
    sum += mean;
    if (mean < it->second.first) {
      ++below;
    } else if (mean > it->second.second) {
      ++above;
    } else {
      ++inside;
    }
  }
  if (test.epochs > 0) {
    const double n = static_cast<double>(test.epochs);
    test.time_average = sum / n;
    test.inside = inside / n;
    test.above = above / n;
    test.below = below / n;
  }
  return test;
}

}  // namespace skerry
