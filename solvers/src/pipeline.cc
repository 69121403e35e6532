#include "skerry/solvers/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "skerry/core/time_order.h"

namespace skerry {

namespace {

// Feeds the recording in time order (core/time_order.h's rule, as the samples and fixes come):
// the sensor blocks due by an IMU sample's time before it (so that each gets its keyframe), then
// the sample, then the fixes before the next one. Fixes and blocks after the last IMU sample are
// left out: nothing would process them. Once `*stop` is set (may be null) nothing more is fed.
// Every few seconds of data what the estimator has made final goes to `sink` if given, else is
// appended to `*kept` (if not null).
struct FeedResult {
  bool stopped = false;
  TimeNs first_imu_ns = 0;
  TimeNs last_fed_ns = 0;  ///< the last IMU sample fed
  bool any_imu = false;
  size_t imu_samples = 0;  ///< read
  size_t gnss_fixes = 0;   ///< read
};

FeedResult Feed(MeasurementStream* input,
                const std::vector<const SensorMeasurement*>& blocks,
                const std::function<void(double)>& progress,
                const std::atomic<bool>* stop,
                const HistorySink& sink,
                EstimatorHistory* kept,
                NavigationEstimator* e) {
  constexpr size_t kProgressEvery = 64;    // samples between looks at the progress
  constexpr size_t kHandOverEvery = 1024;  // samples between hand-overs to the sink
  FeedResult r;
  GnssFix fix;
  const auto next_fix = [&]() {
    const bool got = input->NextGnss(&fix);
    r.gnss_fixes += got;
    return got;
  };
  bool have_fix = next_fix();
  ImuSample s;
  size_t k = 0, b = 0;
  double reported = -1.0;
  EstimatorHistory piece;
  while (input->NextImu(&s)) {
    ++r.imu_samples;
    if (stop != nullptr && stop->load(std::memory_order_relaxed)) {
      r.stopped = true;
      break;
    }
    // A fix before this sample has a sample after it: its time is inside the IMU record.
    for (; have_fix && fix.t_ns < s.t_ns; have_fix = next_fix()) e->AddGnss(fix);
    if (!r.any_imu) r.first_imu_ns = s.t_ns;
    r.any_imu = true;
    r.last_fed_ns = s.t_ns;
    for (; b < blocks.size() && blocks[b]->t_ns <= s.t_ns; ++b) e->AddMeasurement(*blocks[b]);
    e->AddImu(s);
    ++k;
    if (progress && k % kProgressEvery == 0) {
      const double f = input->Fraction();
      if (f >= reported + 0.01) progress(reported = f);
    }
    if (k % kHandOverEvery == 0) {
      if (sink) {
        e->TakeFinal(&piece);
        if (!piece.empty()) sink(piece);
        piece.clear();
      } else if (kept != nullptr) {
        e->TakeFinal(kept);
      }
    }
  }
  if (!r.stopped) {
    // The fixes after the last sample are read (and checked, as a whole-file load would) and
    // counted, not used.
    while (have_fix) have_fix = next_fix();
    if (progress) progress(1.0);
  }
  return r;
}

// Room for the history of a run over `data` without a sink: one record (and one stats entry) per
// keyframe, on the grid or at a sensor block, and one decision per fix. Reserved up front, the
// records (2 kB each, 70 MB for an hour at 10 Hz) are written once; held by the estimator until
// the end, they were copied at every doubling of its vector and once more when taken out of it
// (a 31 ms update when a doubling fell on it).
void ReserveHistory(const Dataset& data,
                    const EstimatorConfig& config,
                    const SensorLog& sensors,
                    EstimatorHistory* history) {
  if (data.imu_samples.size() < 2 || !(config.keyframe_rate_hz > 0.0)) return;
  const double span_s = NsToSeconds(data.imu_samples.back().t_ns - data.imu_samples.front().t_ns);
  const double keyframes = span_s * config.keyframe_rate_hz + 2.0 + sensors.measurements.size();
  if (!(keyframes < 1e9)) return;
  history->outputs.reserve(static_cast<size_t>(keyframes));
  history->stats.reserve(static_cast<size_t>(keyframes));
  history->decisions.reserve(data.gnss_fixes.size());
}

}  // namespace

WindowRun RunWindow(const Dataset& data,
                    const EstimatorConfig& config,
                    const std::function<void(double)>& progress,
                    const EstimateRecord* initial,
                    const SensorLog& sensors,
                    const std::atomic<bool>* stop) {
  InMemoryStream input(data);
  return RunWindow(&input, data, config, progress, initial, sensors, stop);
}

WindowRun RunWindow(MeasurementStream* input,
                    const Dataset& data,
                    const EstimatorConfig& config,
                    const std::function<void(double)>& progress,
                    const EstimateRecord* initial,
                    const SensorLog& sensors,
                    const std::atomic<bool>* stop,
                    const HistorySink& sink) {
  const auto t0 = std::chrono::steady_clock::now();
  NavigationEstimator estimator(config, data.imu, data.gnss, data.Earth());
  for (const SensorSpec& spec : sensors.sensors) estimator.RegisterSensor(spec);
  if (initial == nullptr && sensors.start) initial = &*sensors.start;
  if (initial != nullptr) estimator.SetInitialState(initial->state, initial->covariance);
  // Without a sink the history is taken over as it becomes final, as with one (the pieces,
  // concatenated, are the whole: NavigationEstimator::TakeFinal), into room reserved for it.
  EstimatorHistory kept;
  if (!sink) ReserveHistory(data, config, sensors, &kept);
  const FeedResult fed =
      Feed(input, InTimeOrder(sensors), progress, stop, sink, sink ? nullptr : &kept, &estimator);
  estimator.Finish();
  WindowRun run;
  run.interrupted = fed.stopped;
  run.interrupted_at_ns = fed.stopped ? fed.last_fed_ns : 0;
  if (sink) {
    EstimatorHistory rest;
    estimator.TakeFinal(&rest);
    if (!rest.empty()) sink(rest);
  } else {
    estimator.TakeFinal(&kept);
    run.records = std::move(kept.outputs);
    run.stats = std::move(kept.stats);
    run.decisions = std::move(kept.decisions);
  }
  run.gnss = estimator.gnss_stats();
  run.events = estimator.events();
  run.sensors.sensors = estimator.sensors();
  run.sensors.measurements = estimator.sensor_measurements();
  run.sensors.decisions = estimator.sensor_decisions();
  run.sensors.frontend_stats = sensors.frontend_stats;
  run.sensors.live_frontend_stats = sensors.live_frontend_stats;
  run.sensors.live_frontend_blocks = sensors.live_frontend_blocks;
  for (const auto& [name, live] : sensors.live_frontend_stats) {
    for (const auto& [key, value] : live()) run.sensors.frontend_stats[name][key] = value;
  }
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
  for (size_t k = 0; k < run.sensors.sensors.size(); ++k) {
    SensorParameterEstimate x;
    x.sensor = static_cast<SensorId>(k);
    if (!(run.sensors.sensors[k].parameter_prior_sigma > 0.0) ||
        !estimator.SensorParameter(x.sensor, &x.value, &x.variance)) {
      continue;
    }
    x.has_variance = std::isfinite(x.variance);
    run.parameters.push_back(x);
  }
  if (estimator.GyroCalibration(&run.gyro_calibration.E, &run.gyro_calibration.covariance)) {
    run.gyro_calibration.estimated = true;
    run.gyro_calibration.has_covariance = run.gyro_calibration.covariance.allFinite();
  }
  run.diverged = estimator.status() == NavigationEstimator::Status::kDiverged;
  run.failure = estimator.failure();
  if (const YawHypothesisBank* bank = estimator.bank(); bank != nullptr && bank->decided()) {
    run.align_decision_t_ns = bank->decision_t_ns();
    run.align_start_t_ns = bank->kept_start_t_ns();
    run.align_weight = bank->scores()[bank->kept()].weight;
    run.align_yaw0_deg = bank->scores()[bank->kept()].yaw0_deg;
    run.align_undecided = bank->undecided();
    run.align_heading_sigma_rad = bank->widened_heading_sigma_rad();
  }
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (fed.any_imu) run.data_s = NsToSeconds(fed.last_fed_ns - fed.first_imu_ns);
  run.imu_samples = fed.imu_samples - (fed.stopped ? 1 : 0);  // the sample that saw the stop
  run.gnss_fixes = fed.gnss_fixes;
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
