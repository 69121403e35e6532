// Embeds skerry as the estimation back end of another program: IMU samples, GNSS fixes and the
// blocks of a third sensor (pose fixes from an external matcher, through the frontend seam) go
// into a NavigationEstimator in time order, and the program reads the newest state back.
//
//   skerry_embed               simulates the built-in "harbour" scenario in memory (seed 1),
//                              with GNSS denied after 30 s and 1 Hz pose fixes instead
//   skerry_embed DATASET_DIR   loads a dataset folder (docs/dataset-format.md) instead
//
// Feeds the first 60 s and prints the newest keyframe every 10 s of data: position in the local
// ENU frame, heading, their 1-sigma, and the position error when the data has ground truth.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <iterator>
#include <vector>

#include "skerry/core/heading.h"
#include "skerry/core/nav_state.h"
#include "skerry/core/time.h"
#include "skerry/frontends/pose_fix_frontend.h"
#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/navigation_estimator.h"

namespace {

constexpr double kRunS = 60.0;
constexpr double kPrintEveryS = 10.0;
constexpr std::uint64_t kSeed = 1;

skerry::Dataset MakeDataset(int argc, char** argv) {
  if (argc > 1) {
    std::printf("dataset: %s\n", argv[1]);
    return skerry::LoadDataset(argv[1]);
  }
  skerry::sim::ScenarioConfig scenario = skerry::sim::LoadScenario("harbour");
  std::printf("scenario file: %s\n", scenario.source_file.c_str());
  // Only what we are going to feed (plus a second, so the last print has data behind it).
  scenario.duration_s = std::min(scenario.duration_s, kRunS + 1.0);
  // GNSS denied after 30 s; a matcher's pose fixes of a mast-top LiDAR at 1 Hz instead.
  scenario.gnss.outages = {{30.0, kRunS}};
  scenario.pose_fixes.enabled = true;
  scenario.pose_fixes.mount.p_b_s = Eigen::Vector3d(0.5, 0.0, 4.0);
  return skerry::sim::Simulate(scenario, kSeed);
}

// The true state nearest in time to t_ns, or nullptr without ground truth.
const skerry::NavState* NearestTruth(const std::vector<skerry::NavState>& truth,
                                     skerry::TimeNs t_ns) {
  if (truth.empty()) return nullptr;
  auto it =
      std::lower_bound(truth.begin(), truth.end(), t_ns,
                       [](const skerry::NavState& s, skerry::TimeNs t) { return s.t_ns < t; });
  if (it == truth.end()) return &truth.back();
  if (it != truth.begin() && t_ns - std::prev(it)->t_ns < it->t_ns - t_ns) --it;
  return &*it;
}

void PrintLatest(const skerry::NavigationEstimator& estimator,
                 const skerry::Dataset& data,
                 double t_s) {
  skerry::EstimateRecord latest;
  if (!estimator.Latest(&latest)) {
    std::printf("t=%5.1f s  not initialised yet\n", t_s);
    return;
  }
  const skerry::NavState& x = latest.state;
  std::printf(
      "t=%5.1f s  keyframe %.2f s  p_w_b [E N U] = [%9.2f %9.2f %7.2f] m  heading %6.2f deg", t_s,
      skerry::NsToSeconds(x.t_ns), x.p_w_b.x(), x.p_w_b.y(), x.p_w_b.z(),
      skerry::HeadingDeg(x.q_w_b));
  if (latest.has_covariance) {
    const auto& P = latest.covariance;
    std::printf("  sigma_p [%.2f %.2f %.2f] m  sigma_heading %.2f deg",
                std::sqrt(P(skerry::kPos, skerry::kPos)),
                std::sqrt(P(skerry::kPos + 1, skerry::kPos + 1)),
                std::sqrt(P(skerry::kPos + 2, skerry::kPos + 2)), skerry::HeadingSigmaDeg(P));
  }
  if (const skerry::NavState* truth = NearestTruth(data.truth_states, x.t_ns)) {
    std::printf("  |error| %.2f m", (x.p_w_b - truth->p_w_b).norm());
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const skerry::Dataset data = MakeDataset(argc, argv);
    if (data.imu_samples.empty()) {
      std::fprintf(stderr, "no IMU samples\n");
      return 1;
    }
    const skerry::EstimatorConfig config = skerry::LoadPreset("default");
    // The dataset's Earth: the local ENU frame at its origin on the rotating WGS84 Earth.
    skerry::NavigationEstimator estimator(config, data.imu, data.gnss, data.Earth());
    // A third sensor registers before the first measurement; its frontend turns each fix into a
    // measurement block on the keyframe at the fix's time (docs/estimator.md, the frontend seam).
    skerry::PoseFixFrontend pose_fixes(data.pose_fix_mount, config.SensorOptionsFor("pose_fixes"),
                                       data.Earth());
    if (data.has_pose_fixes) pose_fixes.Register(&estimator);

    // Merge the two streams in time order, as skerry's own pipeline does: on equal times the
    // IMU sample goes first, since a fix is received after the IMU sample of its epoch.
    const skerry::TimeNs t0_ns = data.imu_samples.front().t_ns;
    const skerry::TimeNs end_ns = t0_ns + skerry::SecondsToNs(kRunS);
    skerry::TimeNs next_print_ns = t0_ns + skerry::SecondsToNs(kPrintEveryS);
    // A block goes in before the IMU sample past its time, so that it gets its own keyframe.
    size_t g = 0, f = 0;
    // A program that runs for days hands the final estimates on (to its log, its display) and
    // lets the estimator forget them, so that its memory does not grow (docs/estimator.md).
    skerry::EstimatorHistory final_part;
    size_t handed_on = 0;
    for (const skerry::ImuSample& s : data.imu_samples) {
      if (s.t_ns > end_ns) break;
      while (g < data.gnss_fixes.size() && data.gnss_fixes[g].t_ns < s.t_ns) {
        estimator.AddGnss(data.gnss_fixes[g++]);
      }
      while (data.has_pose_fixes && f < data.pose_fixes.size() &&
             data.pose_fixes[f].t_ns <= s.t_ns) {
        estimator.AddMeasurement(pose_fixes.Measurement(data.pose_fixes[f++]));
      }
      estimator.AddImu(s);
      if (s.t_ns >= next_print_ns) {
        PrintLatest(estimator, data, skerry::NsToSeconds(s.t_ns - t0_ns));
        next_print_ns += skerry::SecondsToNs(kPrintEveryS);
        estimator.TakeFinal(&final_part);
        handed_on += final_part.outputs.size();
        final_part.clear();
      }
    }

    estimator.Finish();
    estimator.TakeFinal(&final_part);
    handed_on += final_part.outputs.size();
    const skerry::GnssStats gnss = estimator.gnss_stats();
    std::printf("%zu keyframes; GNSS fixes accepted %d, rejected %d, dropped %d\n", handed_on,
                gnss.accepted, gnss.rejected, gnss.dropped);
    if (data.has_pose_fixes) {
      const skerry::SensorStats st = estimator.sensor_stats().at(0);
      std::printf("pose fixes accepted %d, rejected %d, dropped %d\n", st.accepted, st.rejected,
                  st.dropped);
    }
    if (estimator.status() == skerry::NavigationEstimator::Status::kDiverged) {
      std::fprintf(stderr, "%s\n", estimator.failure().c_str());
      return 1;
    }
    if (handed_on == 0) {
      std::fprintf(stderr, "the estimator never initialised\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
