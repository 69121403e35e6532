#include "skerry/solvers/pipeline.h"

#include <algorithm>
#include <chrono>

#include "skerry/core/time_order.h"

namespace skerry {

namespace {

// Feeds the recording in time order (core/time_order.h), reporting progress by IMU sample: the
// sensor blocks due by an IMU sample's time before it (so that each gets its keyframe), then the
// sample, then the fixes up to the next one. Fixes and blocks after the last IMU sample are left
// out: nothing would process them. Once `*stop` is set (may be null) nothing more is fed; returns
// the time of the last sample fed then (-1: not stopped).
template <typename Estimator>
TimeNs Feed(const Dataset& data,
            const std::vector<const SensorMeasurement*>& blocks,
            const std::function<void(double)>& progress,
            const std::atomic<bool>* stop,
            Estimator* e) {
  const size_t n = data.imu_samples.size();
  const size_t report_every = std::max<size_t>(n / 100, 1);
  const TimeNs t_last = n > 0 ? data.imu_samples.back().t_ns : 0;
  size_t k = 0, b = 0;
  TimeNs stopped_at = -1, t_fed = n > 0 ? data.imu_samples.front().t_ns : 0;
  ForEachInTimeOrder(
      data.imu_samples, data.gnss_fixes,
      [&](const ImuSample& s) {
        if (stopped_at >= 0) return;
        if (stop != nullptr && stop->load(std::memory_order_relaxed)) {
          stopped_at = t_fed;
          return;
        }
        t_fed = s.t_ns;
        for (; b < blocks.size() && blocks[b]->t_ns <= s.t_ns; ++b) e->AddMeasurement(*blocks[b]);
        e->AddImu(s);
        if (progress && k % report_every == 0) progress(static_cast<double>(k) / n);
        ++k;
      },
      [&](const GnssFix& f) {
        if (stopped_at < 0 && f.t_ns < t_last) e->AddGnss(f);
      });
  if (progress && stopped_at < 0) progress(1.0);
  return stopped_at;
}

}  // namespace

WindowRun RunWindow(const Dataset& data,
                    const EstimatorConfig& config,
                    const std::function<void(double)>& progress,
                    const EstimateRecord* initial,
                    const SensorLog& sensors,
                    const std::atomic<bool>* stop) {
  const auto t0 = std::chrono::steady_clock::now();
  NavigationEstimator estimator(config, data.imu, data.gnss, data.Earth());
  for (const SensorSpec& spec : sensors.sensors) estimator.RegisterSensor(spec);
  if (initial == nullptr && sensors.start) initial = &*sensors.start;
  if (initial != nullptr) estimator.SetInitialState(initial->state, initial->covariance);
  const TimeNs stopped_at = Feed(data, InTimeOrder(sensors), progress, stop, &estimator);
  estimator.Finish();
  WindowRun run;
  run.interrupted = stopped_at >= 0;
  run.interrupted_at_ns = std::max<TimeNs>(stopped_at, 0);
  run.records = estimator.outputs();
  run.stats = estimator.update_stats();
  run.gnss = estimator.gnss_stats();
  run.decisions = estimator.fix_decisions();
  run.events = estimator.events();
  run.sensors.sensors = estimator.sensors();
  run.sensors.measurements = estimator.sensor_measurements();
  run.sensors.decisions = estimator.sensor_decisions();
  run.sensors.frontend_stats = sensors.frontend_stats;
  run.sensor_stats = estimator.sensor_stats();
  for (size_t k = 0; k < run.sensors.sensors.size(); ++k) {
    ExtrinsicEstimate x;
    x.sensor = static_cast<SensorId>(k);
    if (!run.sensors.sensors[k].calibrate ||
        !estimator.SensorExtrinsic(x.sensor, &x.q_b_s, &x.p_b_s, &x.covariance)) {
      continue;
    }
    x.has_covariance = x.covariance.allFinite();
    run.extrinsics.push_back(x);
  }
  run.diverged = estimator.status() == NavigationEstimator::Status::kDiverged;
  run.failure = estimator.failure();
  if (const YawHypothesisBank* bank = estimator.bank(); bank != nullptr && bank->decided()) {
    run.align_decision_t_ns = bank->decision_t_ns();
    run.align_start_t_ns = bank->winner()->outputs().front().state.t_ns;
    run.align_yaw0_deg = bank->scores()[bank->kept()].yaw0_deg;
    run.align_weight = bank->scores()[bank->kept()].weight;
    run.align_undecided = bank->undecided();
    run.align_heading_sigma_rad = bank->widened_heading_sigma_rad();
  }
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const size_t n = data.imu_samples.size();
  if (n > 1) {
    const TimeNs t_end = run.interrupted ? run.interrupted_at_ns : data.imu_samples.back().t_ns;
    run.data_s = NsToSeconds(t_end - data.imu_samples.front().t_ns);
  }
  return run;
}

BatchResult SmoothUntil(const Dataset& data,
                        const EstimatorConfig& config,
                        const WindowRun& window,
                        TimeNs t_end_ns) {
  // Only the window's first record, the prior its start rule gave (the kept hypothesis' for
  // init.mode align), goes in; the rest is the batch's own.
  if (window.records.empty()) return BatchResult();
  EstimateRecord start = window.records.front();
  // An undecided bank's kept hypothesis is only as sure of its heading as the bank's spread
  // (the window was widened to it at the decision; its first record was not).
  const double s = window.align_heading_sigma_rad;
  if (window.align_undecided && start.has_covariance &&
      s * s > start.covariance(kRot + 2, kRot + 2)) {
    start.covariance(kRot + 2, kRot + 2) = s * s;
  }
  SensorLog sensors = window.sensors;
  sensors.decisions.clear();  // the batch judges every block itself
  return SmoothFrom(data, config, start, t_end_ns, sensors);
}

}  // namespace skerry
