#include "skerry/solvers/batch_smoother.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "skerry/core/chi_square.h"
#include "skerry/core/csv_reader.h"
#include "skerry/factors/bias_random_walk_factor.h"
#include "skerry/factors/gnss_drift_factor.h"
#include "skerry/factors/imu_factor.h"
#include "skerry/factors/imu_preintegration.h"
#include "skerry/factors/state_prior_factor.h"
#include "skerry/solvers/nav_graph.h"

namespace skerry {

namespace {
double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

BatchResult SmoothBatch(const Dataset& data,
                        const EstimatorConfig& config,
                        const std::vector<EstimateRecord>& initial,
                        const std::vector<FixRecord>& decisions) {
  BatchResult result;
  if (initial.size() < 2) return result;
  if (decisions.size() > data.gnss_fixes.size()) {
    throw std::logic_error("SmoothBatch: more fix decisions than fixes");
  }
  const EarthModel earth = data.Earth();
  const bool drift = config.gnss_drift.enabled();
  NavGraph graph(drift);
  std::vector<KeyframeId> ids;
  std::vector<TimeNs> times;

  // Keyframes at the window's keyframe times; IMU factors between them.
  const std::vector<ImuSample>& imu = data.imu_samples;
  auto sample_at = [&imu](TimeNs t) {
    return std::lower_bound(imu.begin(), imu.end(), t,
                            [](const ImuSample& s, TimeNs v) { return s.t_ns < v; });
  };
  auto it = sample_at(initial.front().state.t_ns);
  for (size_t k = 0; k < initial.size(); ++k) {
    const NavState& s = initial[k].state;
    auto s_it = sample_at(s.t_ns);
    if (s_it == imu.end()) break;
    const Keyframe& kf = graph.AddKeyframe(s, KeyframeGyro(imu.begin(), std::next(s_it)));
    if (k == 0) {
      graph.AddFactor(FactorKind::kStatePrior, StatePriorFactor::Create(s, initial[0].covariance),
                      nullptr,
                      {{kf.id, Slot::kQ},
                       {kf.id, Slot::kP},
                       {kf.id, Slot::kV},
                       {kf.id, Slot::kBg},
                       {kf.id, Slot::kBa}});
      if (drift) {
        graph.AddFactor(FactorKind::kGnssDriftPrior,
                        std::make_unique<GnssDriftPriorFactor>(config.gnss_drift), nullptr,
                        {{kf.id, Slot::kGb}});
      }
    } else {
      const KeyframeId prev = ids.back();
      const NavState& sp = initial[k - 1].state;
      auto pim = std::make_shared<ImuPreintegration>(data.imu.noise, sp.bg, sp.ba);
      for (auto a = it; a != s_it; ++a) IntegrateBetween(*a, *std::next(a), pim.get());
      graph.AddFactor(FactorKind::kImu,
                      ImuFactor::Create(pim, data.imu, graph.keyframe(prev).gyro_rad_s,
                                        kf.gyro_rad_s, EarthTermsNear(earth, sp.p_w_b)),
                      nullptr,
                      {{prev, Slot::kQ},
                       {prev, Slot::kP},
                       {prev, Slot::kV},
                       {prev, Slot::kBg},
                       {prev, Slot::kBa},
                       {kf.id, Slot::kQ},
                       {kf.id, Slot::kP},
                       {kf.id, Slot::kV}});
      graph.AddFactor(
          FactorKind::kBiasRandomWalk,
          std::make_unique<BiasRandomWalkFactor>(data.imu.noise, pim->dt_s()), nullptr,
          {{prev, Slot::kBg}, {prev, Slot::kBa}, {kf.id, Slot::kBg}, {kf.id, Slot::kBa}});
      if (drift) {
        graph.AddFactor(FactorKind::kGnssDrift,
                        std::make_unique<GnssDriftFactor>(config.gnss_drift, pim->dt_s()), nullptr,
                        {{prev, Slot::kGb}, {kf.id, Slot::kGb}});
      }
    }
    ids.push_back(kf.id);
    times.push_back(s.t_ns);
    it = s_it;
  }

  // GNSS fixes the window did not reject, each on its nearest keyframe; a heading only where
  // the window took it too. decisions[k] is about data.gnss_fixes[k] (the window saw the fixes
  // in this order); fixes after the last decision (the window never saw them) are left out.
  std::vector<FactorId> gnss_factors;
  for (size_t f = 0; f < decisions.size(); ++f) {
    const GnssFix& fix = data.gnss_fixes[f];
    const FixRecord& d = decisions[f];
    if (d.t_ns != fix.t_ns) {
      throw std::logic_error("SmoothBatch: fix decision " + std::to_string(f) +
                             " is not about the fix at t=" + FormatSeconds(fix.t_ns));
    }
    if (d.position == FixDecision::kRejectedByGate || d.position == FixDecision::kDropped) continue;
    auto t_it = std::lower_bound(times.begin(), times.end(), fix.t_ns);
    size_t k = static_cast<size_t>(t_it - times.begin());
    if (k == times.size()) {
      if (fix.t_ns - times.back() > SecondsToNs(1.0 / config.keyframe_rate_hz)) continue;
      k = times.size() - 1;
    } else if (k > 0 && (fix.t_ns - times[k - 1]) < (times[k] - fix.t_ns)) {
      --k;
    }
    if (k == 0 && fix.t_ns < times[0] - SecondsToNs(0.5 / config.keyframe_rate_hz)) continue;
    const Keyframe& kf = graph.keyframe(ids[k]);
    const TiedFix tied = TieFix(fix, kf, data.gnss, data.imu, earth, config.gnss_sigma_scale);
    gnss_factors.push_back(graph.AddFactor(FactorKind::kGnssPosition, GnssPositionCost(fix, tied),
                                           MakeLoss(config.gnss_loss), GnssPositionBlocks(kf.id)));
    if (d.heading == HeadingDecision::kAccepted) {
      graph.AddFactor(FactorKind::kGnssHeading, GnssHeadingCost(fix, tied),
                      MakeLoss(config.heading_loss), {{kf.id, Slot::kQ}});
      ++result.headings_used;
    }
  }

  const auto t_solve = std::chrono::steady_clock::now();
  ceres::Solver::Summary summary = graph.Solve(config.batch_ceres);
  result.iterations = StepsTried(summary);
  // Chi-square check at the solution: drop fixes whose whitened residual is an outlier, re-solve.
  if (config.gnss_gate_probability > 0.0) {
    const double gate = ChiSquareQuantile(config.gnss_gate_probability, 3.0);
    std::vector<FactorId> kept;
    for (FactorId f : gnss_factors) {
      if (graph.FactorResidual(f).squaredNorm() > gate) {
        graph.RemoveFactor(f);
        ++result.gnss_rejected_after_solve;
      } else {
        kept.push_back(f);
      }
    }
    gnss_factors = kept;
    if (result.gnss_rejected_after_solve > 0) {
      summary = graph.Solve(config.batch_ceres);
      result.iterations += StepsTried(summary);
    }
  }
  result.solve_s = SecondsSince(t_solve);
  result.gnss_used = static_cast<int>(gnss_factors.size());
  result.usable = summary.IsSolutionUsable();
  result.ceres_report = summary.BriefReport();

  const auto t_cov = std::chrono::steady_clock::now();
  std::vector<StateCovariance> covs;
  const bool have_cov = config.compute_covariance && graph.AllCovariances(&covs);
  result.covariance_s = SecondsSince(t_cov);
  for (size_t k = 0; k < ids.size(); ++k) {
    EstimateRecord r;
    r.state = graph.keyframe(ids[k]).state();
    r.has_covariance = have_cov;
    if (have_cov) r.covariance = covs[k];
    result.records.push_back(r);
  }
  return result;
}

}  // namespace skerry
