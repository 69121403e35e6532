#include "skerry/solvers/batch_smoother.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "skerry/core/chi_square.h"
#include "skerry/factors/factor_linearization.h"
#include "skerry/factors/gnss_drift_factor.h"
#include "skerry/factors/imu_preintegration.h"
#include "skerry/factors/state_prior_factor.h"
#include "skerry/io/csv_reader.h"
#include "skerry/solvers/innovation_gate.h"
#include "skerry/solvers/keyframe_policy.h"
#include "skerry/solvers/motion_factors.h"
#include "skerry/solvers/nav_graph.h"

namespace skerry {

namespace {

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// A block that is not in the batch, as BatchResult::sensor_decisions lists it.
SensorRecord DroppedRecord(const SensorMeasurement& m) {
  SensorRecord r;
  r.sensor = m.sensor;
  r.t_ns = m.t_ns;
  r.decision = SensorDecision::kDropped;
  return r;
}

// The blocks not in the batch among those Finish listed, all in time order.
void MergeDecisions(std::vector<SensorRecord> dropped, BatchResult* result) {
  std::vector<SensorRecord>& all = result->sensor_decisions;
  all.insert(all.end(), dropped.begin(), dropped.end());
  std::stable_sort(all.begin(), all.end(),
                   [](const SensorRecord& a, const SensorRecord& b) { return a.t_ns < b.t_ns; });
}

// The batch's graph: keyframes at IMU samples, the window's factors between them, fixes tied to
// the nearest keyframe. One builder for SmoothBatch (keyframes and guesses from the window) and
// SmoothFrom (its own keyframes, predicted through the IMU; SmoothUntil's engine).
class BatchGraph {
 public:
  BatchGraph(const Dataset& data,
             const EstimatorConfig& config,
             const std::vector<SensorSpec>& sensors)
      : data_(data),
        config_((ValidateEstimatorConfig(config), config)),  // std::invalid_argument if it is wrong
        earth_(data.Earth()),
        graph_(config.gnss_drift.enabled()),
        half_period_ns_(SecondsToNs(0.5 / config.keyframe_rate_hz)),
        sensors_(sensors),
        policy_(config.keyframe_rate_hz) {
    for (size_t k = 0; k < sensors_.size(); ++k) {
      AddSensorExtrinsic(&graph_, static_cast<SensorId>(k), sensors_[k]);
      AddSensorParameter(&graph_, static_cast<SensorId>(k), sensors_[k]);
    }
    if (EstimatesGyroCalibration(config_, data_.imu)) AddImuCalibration(&graph_, data_.imu);
  }

  // The newest keyframe's time.
  TimeNs newest_t_ns() const { return times_.back(); }
  TimeNs half_period_ns() const { return half_period_ns_; }

  size_t SampleAt(TimeNs t) const {
    const std::vector<ImuSample>& imu = data_.imu_samples;
    return static_cast<size_t>(
        std::lower_bound(imu.begin(), imu.end(), t,
                         [](const ImuSample& s, TimeNs v) { return s.t_ns < v; }) -
        imu.begin());
  }

  // The first keyframe, at IMU sample `sample`, with a prior on its state.
  void Start(size_t sample, const NavState& state, const StateCovariance& covariance) {
    NavState s = state;
    s.t_ns = data_.imu_samples.at(sample).t_ns;
    const Keyframe& kf = AddKeyframe(s);
    graph_.AddFactor(FactorKind::kStatePrior, StatePriorFactor::Create(s, covariance), nullptr,
                     {{kf.id, Slot::kQ},
                      {kf.id, Slot::kP},
                      {kf.id, Slot::kV},
                      {kf.id, Slot::kBg},
                      {kf.id, Slot::kBa}});
    if (config_.gnss_drift.enabled()) {
      graph_.AddFactor(FactorKind::kGnssDriftPrior,
                       std::make_unique<GnssDriftPriorFactor>(config_.gnss_drift), nullptr,
                       {{kf.id, Slot::kGb}});
    }
  }

  // A keyframe at time t after the newest (an IMU sample's, or a sensor block's between two:
  // keyframe_policy.h), linked to it by the IMU, bias and drift factors; its initial value is
  // `guess`, or the newest state predicted through the IMU.
  void Extend(TimeNs t, const NavState* guess) {
    const KeyframeId prev = ids_.back();
    const NavState sp = graph_.keyframe(prev).state();
    ImuPreintegration pim(data_.imu.noise, sp.bg, sp.ba, graph_.has_imu_calibration());
    IntegrateSpan(times_.back(), t, &pim);
    const Eigen::Vector3d gyro = GyroAt(t);
    const ImuEarthTerms earth = EarthTermsNear(earth_, sp.p_w_b);
    NavState s = sp;
    if (guess != nullptr) {
      s = *guess;
    } else {
      PredictBodyState(pim, data_.imu, earth, graph_.keyframe(prev).gyro_rad_s, gyro, sp.q_w_b,
                       sp.p_w_b, sp.v_w, sp.bg, sp.ba, &s.q_w_b, &s.p_w_b, &s.v_w,
                       graph_.has_imu_calibration() ? graph_.imu_calibration().value : nullptr);
    }
    s.t_ns = t;
    const KeyframeId id = AddKeyframe(s).id;
    AddMotionFactors(&graph_, prev, id, pim, data_.imu, graph_.keyframe(prev).gyro_rad_s, gyro,
                     earth, config_.gnss_drift);
  }

  // A sensor block on the keyframe at its time (within the policy's merge tolerance); false when
  // there is none. `active`: in from the start (SmoothBatch: the window accepted it).
  bool AddSensorBlock(const SensorMeasurement& m, bool active) {
    const auto it =
        std::lower_bound(times_.begin(), times_.end(), m.t_ns - policy_.merge_tolerance_ns());
    if (it == times_.end() || !policy_.Merges(m.t_ns, *it)) return false;
    TiedBlock b;
    b.measurement = m;
    b.keyframe = ids_[static_cast<size_t>(it - times_.begin())];
    const Keyframe& kf = graph_.keyframe(b.keyframe);
    if (!PrepareMeasurement(sensors_.at(m.sensor), &b.measurement, kf.state(), kf.gyro_rad_s,
                            BlockConsumer::kBatch)) {
      return false;
    }
    blocks_.push_back(b);
    if (active) ActivateBlock(&blocks_.back(), true);
    return true;
  }

  // Ties a fix to its nearest keyframe and adds its position factor (and heading factor if
  // `with_heading`); false when no keyframe is within half a period of it.
  bool AddFix(const GnssFix& fix, bool with_heading) {
    auto t_it = std::lower_bound(times_.begin(), times_.end(), fix.t_ns);
    size_t k = static_cast<size_t>(t_it - times_.begin());
    if (k == times_.size()) {
      if (fix.t_ns - times_.back() > half_period_ns_) return false;
      k = times_.size() - 1;
    } else if (k > 0 && (fix.t_ns - times_[k - 1]) < (times_[k] - fix.t_ns)) {
      --k;
    }
    if (k == 0 && fix.t_ns < times_[0] - half_period_ns_) return false;
    TiedMeasurement m;
    m.fix = fix;
    m.keyframe = ids_[k];
    m.tied = TieFix(fix, graph_.keyframe(m.keyframe), data_.gnss, data_.imu, earth_,
                    config_.gnss_sigma_scale);
    m.with_heading = with_heading;
    fixes_.push_back(m);
    Activate(&fixes_.back(), true, true);
    return true;
  }

  // Solves with the gate on: every fix decided anew at the solution, in when its whitened
  // residual there is inside the gate (chi2_3 for a position, chi2_1 for a heading), out
  // otherwise, a fix left out earlier coming back when the solution has moved to it; the same for
  // the sensor blocks by their own gates. Up to `rounds` times a decision changes the problem
  // and the solve goes on. With the chain solver the decisions are made inside its iterations
  // (NavGraph::SolveChain's `decide`: at the near-converged iterates and at the converged one),
  // so a round costs no linearisation of its own; with Ceres' solvers, whose problem cannot
  // change inside a solve, after each solve, re-solving while the decisions change.
  // `only_if_converged`: no decisions at a solution the solver did not converge to (a span cut
  // short by its iteration cap is not where a fix should be judged: with a navigation-grade IMU
  // five iterations never converge, and deciding there threw out every fix of the harbour run);
  // these are made after the solve, as with Ceres.
  ceres::Solver::Summary SolveAndDecide(const CeresConfig& solver,
                                        int rounds,
                                        BatchResult* result,
                                        bool only_if_converged = false) {
    const bool gated = config_.gnss_gate_probability > 0.0 || !blocks_.empty();
    if (gated && !only_if_converged && solver.linear_solver == "chain") {
      int rounds_left = rounds;
      int calls = 0;
      const ceres::Solver::Summary summary = graph_.SolveChain(solver, [&]() -> int {
        if (rounds_left == 0) return 0;
        ++calls;
        const int changed = DecideAll();
        spdlog::debug("batch: gate decisions, call {}, {} changed", calls, changed);
        if (changed > 0) --rounds_left;
        return changed;
      });
      result->iterations += StepsTried(summary);
      spdlog::debug(
          "batch: solve with the gate inside, {} iterations, {} gate rounds, cost {:.6g} "
          "-> {:.6g} ({})",
          StepsTried(summary), rounds - rounds_left, summary.initial_cost, summary.final_cost,
          summary.message);
      if (graph_.stopped()) result->interrupted = true;
      return summary;
    }
    ceres::Solver::Summary summary = graph_.Solve(solver);
    result->iterations += StepsTried(summary);
    spdlog::debug("batch: solve, {} iterations, cost {:.6g} -> {:.6g} ({})", StepsTried(summary),
                  summary.initial_cost, summary.final_cost, summary.message);
    if (graph_.stopped()) {
      result->interrupted = true;
      return summary;
    }
    if (!gated) return summary;
    if (only_if_converged && summary.termination_type != ceres::CONVERGENCE) return summary;
    for (int round = 0; round < rounds; ++round) {
      const int changed = DecideAll();
      if (changed == 0) break;
      summary = graph_.Solve(solver);
      result->iterations += StepsTried(summary);
      spdlog::debug(
          "batch: gate round {}, {} decisions changed, {} iterations, cost {:.6g} -> {:.6g} ({})",
          round + 1, changed, StepsTried(summary), summary.initial_cost, summary.final_cost,
          summary.message);
      if (graph_.stopped()) {
        result->interrupted = true;
        break;
      }
    }
    return summary;
  }

  // Decides every fix and sensor block anew at the current estimate (SolveAndDecide) and puts
  // their factors in or takes them out; returns how many decisions changed.
  int DecideAll() {
    const double p = config_.gnss_gate_probability > 0.0 ? config_.gnss_gate_probability : 0.5;
    const double gate3 = ChiSquareQuantile(p, 3.0);
    const double gate1 = ChiSquareQuantile(p, 1.0);
    int changed = 0;
    for (TiedMeasurement& m : fixes_) {
      if (!(config_.gnss_gate_probability > 0.0)) break;
      const bool position_in =
          Whitened(*GnssPositionCost(m.fix, m.tied), GnssPositionBlocks(m.keyframe)) <= gate3;
      const bool heading_in = m.with_heading && Whitened(*GnssHeadingCost(m.fix, m.tied),
                                                         {{m.keyframe, Slot::kQ}}) <= gate1;
      changed += (position_in != (m.position >= 0)) +
                 (m.with_heading && position_in && heading_in != (m.heading >= 0));
      Activate(&m, position_in, position_in && heading_in);
    }
    for (TiedBlock& b : blocks_) {
      const SensorSpec& spec = sensors_.at(b.measurement.sensor);
      if (!(spec.gate_probability > 0.0)) continue;
      const std::vector<BlockRef> refs = SensorBlocks(spec, b.measurement, b.keyframe);
      int dof = b.measurement.cost->num_residuals();
      double d2 =
          spec.gate_space == GateSpace::kState
              ? StateSpaceWhitened(*b.measurement.cost, refs, b.measurement.slots.size(), &dof)
              : Whitened(*b.measurement.cost, refs);
      // A down-weighted block is judged by its own noise (SensorMeasurement::gate_scale).
      d2 /= b.measurement.gate_scale * b.measurement.gate_scale;
      b.dim = dof;
      b.d2 = d2;
      const bool in = d2 <= ChiSquareQuantile(spec.gate_probability, dof);
      changed += in != (b.factor >= 0);
      ActivateBlock(&b, in);
    }
    return changed;
  }

  void Finish(const ceres::Solver::Summary& summary, BatchResult* result) {
    for (const TiedMeasurement& m : fixes_) {
      result->gnss_used += m.position >= 0;
      result->headings_used += m.heading >= 0;
      result->gnss_rejected_after_solve += m.position < 0;
    }
    result->sensor_used.assign(sensors_.size(), 0);
    result->sensor_rejected_after_solve.assign(sensors_.size(), 0);
    for (const TiedBlock& b : blocks_) {
      (b.factor >= 0 ? result->sensor_used
                     : result->sensor_rejected_after_solve)[b.measurement.sensor]++;
      SensorRecord r;
      r.sensor = b.measurement.sensor;
      r.t_ns = b.measurement.t_ns;
      r.decision = b.factor >= 0 ? SensorDecision::kAccepted : SensorDecision::kRejectedByGate;
      r.dim = b.dim > 0 ? b.dim : b.measurement.cost->num_residuals();
      r.d2 = b.dim > 0 ? b.d2 : 0.0;
      result->sensor_decisions.push_back(r);
    }
    result->records.reserve(result->records.size() + ids_.size());
    const size_t first = result->records.size();
    for (const KeyframeId id : ids_) {
      EstimateRecord r;
      r.state = graph_.keyframe(id).state();
      result->records.push_back(r);
    }
    // The keyframes' covariances first: their pass finds the sensor blocks' joint marginal on
    // the way (NavGraph::SensorBlocksCovariance), which then needs no pass of its own (a forward
    // elimination of the whole chain each: 4.5 % of a harbour smooth's instructions for the
    // gyro's calibration alone). Without the covariances, or where it was not found, each
    // sensor block's own pass (ExtrinsicCovariance and its kin).
    const auto t_cov = std::chrono::steady_clock::now();
    NavGraph::SensorBlocksCovariance joint;
    const bool have_cov =
        config_.compute_covariance &&
        graph_.AllCovariances(
            [&](size_t k, const StateCovariance& P) { result->records[first + k].covariance = P; },
            &joint);
    if (!have_cov) joint.covariance.resize(0, 0);
    result->covariance_s = SecondsSince(t_cov);
    for (size_t k = first; k < result->records.size(); ++k) {
      result->records[k].has_covariance = have_cov;
      if (!have_cov) result->records[k].covariance.setZero();
    }
    Eigen::MatrixXd marginal;
    for (size_t k = 0; k < sensors_.size(); ++k) {
      Eigen::Matrix<double, 6, 6> cov;
      if (!graph_.has_extrinsic(static_cast<SensorId>(k))) continue;
      ExtrinsicEstimate x;
      x.sensor = static_cast<SensorId>(k);
      x.q_b_s = graph_.extrinsic(x.sensor).q_b_s();
      x.p_b_s = graph_.extrinsic(x.sensor).p_b_s();
      if (joint.Of(ExtrinsicBlocks(x.sensor), &marginal)) {
        x.has_covariance = true;
        x.covariance = marginal;
      } else {
        x.has_covariance = graph_.ExtrinsicCovariance(x.sensor, &cov);
        if (x.has_covariance) x.covariance = cov;
      }
      result->extrinsics.push_back(x);
    }
    for (size_t k = 0; k < sensors_.size(); ++k) {
      const SensorId id = static_cast<SensorId>(k);
      if (!graph_.has_sensor_parameter(id) || !graph_.sensor_parameter(id).estimated) continue;
      SensorParameterEstimate x;
      x.sensor = id;
      x.value = graph_.sensor_parameter(id).value[0];
      if (joint.Of({SensorParameterBlock(id)}, &marginal)) {
        x.has_variance = true;
        x.variance = marginal(0, 0);
      } else {
        x.has_variance = graph_.SensorParameterVariance(id, &x.variance);
      }
      result->parameters.push_back(x);
    }
    if (graph_.has_imu_calibration()) {
      GyroCalibrationEstimate& g = result->gyro_calibration;
      g.estimated = true;
      g.E = Eigen::Map<const Eigen::Matrix3d>(graph_.imu_calibration().value);
      if (joint.Of({ImuCalibrationBlock()}, &marginal)) {
        g.has_covariance = true;
        g.covariance = marginal;
      } else {
        g.has_covariance = graph_.ImuCalibrationCovariance(&g.covariance);
      }
    }
    result->usable = summary.IsSolutionUsable();
    result->ceres_report = summary.BriefReport();
  }

  bool empty() const { return ids_.empty(); }
  void set_stop(const std::atomic<bool>* stop) { graph_.set_stop(stop); }
  const KeyframePolicy& policy() const { return policy_; }

 private:
  const Keyframe& AddKeyframe(const NavState& s) {
    const Keyframe& kf = graph_.AddKeyframe(s, GyroAt(s.t_ns));
    ids_.push_back(kf.id);
    times_.push_back(s.t_ns);
    return kf;
  }

  // The IMU sample at t: a recorded one, or interpolated between its neighbours.
  ImuSample SampleAtTime(TimeNs t) const {
    const std::vector<ImuSample>& imu = data_.imu_samples;
    const size_t k = SampleAt(t);
    if (k >= imu.size()) return imu.back();
    if (imu[k].t_ns == t || k == 0) return imu[k];
    return InterpolateSample(imu[k - 1], imu[k], t);
  }

  // Preintegrates [t0, t1] over the recorded samples, with samples interpolated at ends that are
  // not on one (the window splits its preintegration the same way).
  void IntegrateSpan(TimeNs t0, TimeNs t1, ImuPreintegration* pim) const {
    const std::vector<ImuSample>& imu = data_.imu_samples;
    ImuSample prev = SampleAtTime(t0);
    for (size_t k = SampleAt(t0); k < imu.size() && imu[k].t_ns <= t1; ++k) {
      if (imu[k].t_ns <= prev.t_ns) continue;
      IntegrateBetween(prev, imu[k], pim);
      prev = imu[k];
    }
    if (prev.t_ns < t1) IntegrateBetween(prev, SampleAtTime(t1), pim);
  }

  // The body rate at a keyframe at t (KeyframeGyro over the recorded samples up to t, and the
  // interpolated one at t when t is between two).
  Eigen::Vector3d GyroAt(TimeNs t) const {
    const std::vector<ImuSample>& imu = data_.imu_samples;
    const size_t k = SampleAt(t);
    if (k < imu.size() && imu[k].t_ns == t) return KeyframeGyro(imu.begin(), imu.begin() + k + 1);
    std::vector<ImuSample> recent;
    for (size_t a = k; a-- > 0 && imu[a].t_ns > t - kKeyframeGyroWindowNs;)
      recent.push_back(imu[a]);
    std::reverse(recent.begin(), recent.end());
    recent.push_back(SampleAtTime(t));
    return KeyframeGyro(recent.begin(), recent.end());
  }

  // A sensor block on its keyframe, and its factor in the graph (-1: left out).
  struct TiedBlock {
    SensorMeasurement measurement;
    KeyframeId keyframe = 0;
    FactorId factor = -1;
    int dim = 0;      // the gate's degrees of freedom at its last evaluation (0: never gated)
    double d2 = 0.0;  // and its innovation there
  };

  void ActivateBlock(TiedBlock* b, bool in) {
    if (in && b->factor < 0) {
      const SensorSpec& spec = sensors_.at(b->measurement.sensor);
      b->factor =
          graph_.AddSharedFactor(FactorKind::kSensor, b->measurement.cost, MakeLoss(spec.loss),
                                 SensorBlocks(spec, b->measurement, b->keyframe));
    } else if (!in && b->factor >= 0) {
      graph_.RemoveFactor(b->factor);
      b->factor = -1;
    }
  }

  // A fix tied to its keyframe, and its factors in the graph (-1: left out).
  struct TiedMeasurement {
    GnssFix fix;
    KeyframeId keyframe = 0;
    TiedFix tied;
    bool with_heading = false;
    FactorId position = -1;
    FactorId heading = -1;
  };

  // Puts a fix's factors in or takes them out.
  void Activate(TiedMeasurement* m, bool position, bool heading) {
    if (position && m->position < 0) {
      m->position = AddGnssPositionFactor(&graph_, m->fix, m->tied, m->keyframe, config_);
    } else if (!position && m->position >= 0) {
      graph_.RemoveFactor(m->position);
      m->position = -1;
    }
    heading = heading && m->with_heading;
    if (heading && m->heading < 0) {
      m->heading = AddGnssHeadingFactor(&graph_, m->fix, m->tied, m->keyframe, config_);
    } else if (!heading && m->heading >= 0) {
      graph_.RemoveFactor(m->heading);
      m->heading = -1;
    }
  }

  // Squared whitened residual of a cost on a keyframe at its current value (no robust loss).
  double Whitened(const ceres::CostFunction& cost, const std::vector<BlockRef>& blocks) const {
    std::vector<const double*> values;
    for (const BlockRef& b : blocks) values.push_back(graph_.BlockValue(b));
    Eigen::VectorXd r(cost.num_residuals());
    if (!cost.Evaluate(values.data(), r.data(), nullptr)) return HUGE_VAL;
    return r.squaredNorm();
  }

  // The same, of its projection on the column space of its Jacobian over the first
  // `state_blocks` blocks, the keyframe's (innovation_gate.h, GateSpace::kState: what a step of
  // the keyframe's state alone would still remove); `*dof`: the rank of that space.
  double StateSpaceWhitened(const ceres::CostFunction& cost,
                            const std::vector<BlockRef>& blocks,
                            size_t state_blocks,
                            int* dof) const {
    std::vector<const double*> values;
    for (const BlockRef& b : blocks) values.push_back(graph_.BlockValue(b));
    LinearizedResidual lin;
    if (!LinearizeResidual(cost, nullptr, values, values, &lin) || !lin.residual.allFinite()) {
      return HUGE_VAL;
    }
    state_blocks = std::min(state_blocks, lin.jacobians.size());
    int cols = 0;
    for (size_t k = 0; k < state_blocks; ++k) cols += static_cast<int>(lin.jacobians[k].cols());
    Eigen::MatrixXd J(lin.residual.size(), cols);
    for (int k = 0, c = 0; k < static_cast<int>(state_blocks); ++k) {
      J.middleCols(c, lin.jacobians[k].cols()) = lin.jacobians[k];
      c += static_cast<int>(lin.jacobians[k].cols());
    }
    const StateSpaceProjection proj = ProjectOnState(lin.residual, J);
    *dof = std::max<int>(1, static_cast<int>(proj.y.size()));
    return proj.y.squaredNorm();
  }

  const Dataset& data_;
  const EstimatorConfig& config_;
  const EarthModel earth_;
  NavGraph graph_;
  const TimeNs half_period_ns_;
  std::vector<KeyframeId> ids_;
  std::vector<TimeNs> times_;
  std::vector<TiedMeasurement> fixes_;
  std::vector<SensorSpec> sensors_;
  std::vector<TiedBlock> blocks_;
  KeyframePolicy policy_;
};

}  // namespace

namespace {

// SmoothBatch over `count` window states, state(k) the k-th, `first_covariance` the first one's:
// one body for the window's records and for a BatchStart, neither copied into the other.
// `built()` is called once the graph is built, before the solve: from then on the batch reads
// neither the states nor the IMU samples.
template <typename StateAt, typename Built>
BatchResult SmoothBatchOver(const Dataset& data,
                            const EstimatorConfig& config,
                            size_t count,
                            StateAt state,
                            const StateCovariance& first_covariance,
                            const std::vector<FixRecord>& decisions,
                            const SensorLog& sensors,
                            const std::atomic<bool>* stop,
                            Built built) {
  BatchResult result;
  if (count < 2) return result;
  if (decisions.size() > data.gnss_fixes.size()) {
    throw std::logic_error("SmoothBatch: more fix decisions than fixes");
  }
  if (!sensors.decisions.empty() && sensors.decisions.size() != sensors.measurements.size()) {
    throw std::logic_error("SmoothBatch: one sensor decision per block");
  }
  // Keyframes at the window's keyframe times, started from its values.
  BatchGraph batch(data, config, sensors.sensors);
  batch.set_stop(stop);
  for (size_t k = 0; k < count; ++k) {
    const NavState& x = state(k);
    if (k > 0 && x.t_ns <= state(k - 1).t_ns) {
      throw std::invalid_argument(
          "SmoothBatch: the initial estimates do not increase in time at t=" +
          FormatSeconds(x.t_ns));
    }
    if (x.t_ns > data.imu_samples.back().t_ns) break;
    if (k == 0) {
      const size_t sample = batch.SampleAt(x.t_ns);
      batch.Start(sample, x, first_covariance);
    } else {
      batch.Extend(x.t_ns, &x);
    }
  }
  std::vector<int> unplaced(sensors.sensors.size(), 0);
  std::vector<SensorRecord> dropped;  // blocks not in the batch (BatchResult::sensor_decisions)
  for (size_t k = 0; k < sensors.measurements.size(); ++k) {
    const SensorDecision d =
        sensors.decisions.empty() ? SensorDecision::kAccepted : sensors.decisions[k].decision;
    const SensorMeasurement& m = sensors.measurements[k];
    if (d == SensorDecision::kDropped) {
      dropped.push_back(DroppedRecord(m));
      continue;
    }
    if (!batch.AddSensorBlock(m, d == SensorDecision::kAccepted)) {
      ++unplaced.at(m.sensor);
      dropped.push_back(DroppedRecord(m));
    }
  }

  // GNSS fixes the window did not reject (nor took across a jump), each on its nearest keyframe;
  // a heading only where the window took it too. decisions[k] is about data.gnss_fixes[k] (the
  // window saw the fixes in this order); fixes after the last decision (the window never saw them)
  // are left out.
  for (size_t f = 0; f < decisions.size(); ++f) {
    const GnssFix& fix = data.gnss_fixes[f];
    const FixRecord& d = decisions[f];
    if (d.t_ns != fix.t_ns) {
      throw std::logic_error("SmoothBatch: fix decision " + std::to_string(f) +
                             " is not about the fix at t=" + FormatSeconds(fix.t_ns));
    }
    if (d.position == FixDecision::kRejectedByGate || d.position == FixDecision::kDropped) continue;
    // Offset by a jump the window carried in its drift as a step: the batch models no steps.
    if (d.across_jump) continue;
    batch.AddFix(fix, d.heading == HeadingDecision::kAccepted);
  }
  built();

  const auto t_solve = std::chrono::steady_clock::now();
  const ceres::Solver::Summary summary = batch.SolveAndDecide(config.batch_ceres, 3, &result);
  result.solve_s = SecondsSince(t_solve);
  batch.Finish(summary, &result);
  result.sensor_unplaced = unplaced;
  MergeDecisions(std::move(dropped), &result);
  return result;
}

}  // namespace

BatchStart BatchStartOf(const std::vector<EstimateRecord>& records) {
  BatchStart start;
  start.states.reserve(records.size());
  for (const EstimateRecord& r : records) start.states.push_back(r.state);
  if (!records.empty()) start.first_covariance = records.front().covariance;
  return start;
}

BatchResult SmoothBatch(const Dataset& data,
                        const EstimatorConfig& config,
                        const std::vector<EstimateRecord>& initial,
                        const std::vector<FixRecord>& decisions,
                        const SensorLog& sensors,
                        const std::atomic<bool>* stop) {
  return SmoothBatchOver(
      data, config, initial.size(),
      [&initial](size_t k) -> const NavState& { return initial[k].state; },
      initial.empty() ? StateCovariance::Zero().eval() : initial.front().covariance, decisions,
      sensors, stop, [] {});
}

BatchResult SmoothBatch(Dataset* data,
                        const EstimatorConfig& config,
                        BatchStart initial,
                        const std::vector<FixRecord>& decisions,
                        const SensorLog& sensors,
                        const std::atomic<bool>* stop) {
  return SmoothBatchOver(
      *data, config, initial.states.size(),
      [&initial](size_t k) -> const NavState& { return initial.states[k]; },
      initial.first_covariance, decisions, sensors, stop,
      [data, &initial] {
        std::vector<ImuSample>().swap(data->imu_samples);
        std::vector<NavState>().swap(initial.states);
      });
}

BatchResult SmoothFrom(const Dataset& data_in,
                       const EstimatorConfig& config,
                       const EstimateRecord& start,
                       TimeNs t_end_ns,
                       const SensorLog& sensors) {
  BatchResult result;
  const Dataset data = DatasetUntil(data_in, t_end_ns);
  BatchGraph batch(data, config, sensors.sensors);
  const size_t first = batch.SampleAt(start.state.t_ns);
  if (first + 1 >= data.imu_samples.size()) return result;
  batch.Start(first, start.state, start.covariance);

  // Keyframes by the window's rule (keyframe_policy.h: the grid, and the time of every sensor
  // block), its own values: predicted through the IMU from the solution so far. The span solved
  // doubles each round (10 s, 20 s, 40 s, ...), so that what is predicted is never longer than
  // what is already solved.
  const std::vector<ImuSample>& imu = data.imu_samples;
  const TimeNs t0 = imu[first].t_ns;
  KeyframePolicy policy(config.keyframe_rate_hz);
  policy.Start(t0);
  const std::vector<const SensorMeasurement*> blocks = InTimeOrder(sensors, t_end_ns);
  size_t sample = first + 1, fix = 0, block_key = 0, block_add = 0;
  std::vector<int> unplaced(sensors.sensors.size(), 0);
  std::vector<SensorRecord> dropped;  // blocks not in the batch (BatchResult::sensor_decisions)
  const bool use_heading = config.use_gnss_heading;
  double span_s = 10.0;
  // The spans before the last only seed the next prediction: a few iterations do.
  CeresConfig growing = config.batch_ceres;
  growing.max_iterations = std::min(growing.max_iterations, 5);
  growing.function_tolerance = std::max(growing.function_tolerance, 1e-6);
  const auto t_solve = std::chrono::steady_clock::now();
  ceres::Solver::Summary summary;
  while (true) {
    const TimeNs horizon = std::min(t0 + SecondsToNs(span_s), imu.back().t_ns);
    for (; sample < imu.size() && imu[sample].t_ns <= horizon; ++sample) {
      const TimeNs t = imu[sample].t_ns;
      for (; block_key < blocks.size() && blocks[block_key]->t_ns <= t; ++block_key) {
        const TimeNs tb = blocks[block_key]->t_ns;
        if (tb <= batch.newest_t_ns() + policy.merge_tolerance_ns()) continue;
        batch.Extend(tb, nullptr);
        policy.Closed(tb, /*on_grid=*/false);
      }
      if (!policy.GridDue(t) || t <= batch.newest_t_ns()) continue;
      batch.Extend(t, nullptr);
      policy.Closed(t, /*on_grid=*/true);
    }
    const bool last = horizon >= imu.back().t_ns;
    for (; fix < data.gnss_fixes.size() && data.gnss_fixes[fix].t_ns <= horizon; ++fix) {
      const GnssFix& f = data.gnss_fixes[fix];
      // A fix nearer the next span's first keyframe than this span's last waits for it.
      if (!last && f.t_ns > batch.newest_t_ns() + batch.half_period_ns()) break;
      batch.AddFix(f, use_heading && f.has_heading);
    }
    for (; block_add < blocks.size() &&
           blocks[block_add]->t_ns <= batch.newest_t_ns() + batch.policy().merge_tolerance_ns();
         ++block_add) {
      if (!batch.AddSensorBlock(*blocks[block_add], true)) {
        ++unplaced.at(blocks[block_add]->sensor);
        dropped.push_back(DroppedRecord(*blocks[block_add]));
      }
    }
    summary = last ? batch.SolveAndDecide(config.batch_ceres, 3, &result)
                   : batch.SolveAndDecide(growing, 1, &result, /*only_if_converged=*/true);
    if (last) break;
    span_s *= 2.0;
  }
  result.solve_s = SecondsSince(t_solve);
  batch.Finish(summary, &result);
  // Blocks after the last keyframe never found one.
  for (; block_add < blocks.size(); ++block_add) {
    ++unplaced.at(blocks[block_add]->sensor);
    dropped.push_back(DroppedRecord(*blocks[block_add]));
  }
  result.sensor_unplaced = unplaced;
  MergeDecisions(std::move(dropped), &result);
  return result;
}

}  // namespace skerry
