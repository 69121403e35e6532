// The LiDAR/aerial frontend end to end on the simulated harbour (skerry simulate's path:
// Simulate, RenderAerialImage, RenderLidarScans, WriteDataset, LoadDataset, DatasetSensors,
// RunWindow) with the lidar-harbour preset, and the bad input a dataset can hold: a LiDAR
// without an orthophoto, a truncated scan.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>

#include "skerry/core/chi_square.h"
#include "skerry/core/heading.h"
#include "skerry/core/input_error.h"
#include "skerry/eval/evaluation.h"
#include "skerry/frontends/dataset_sensors.h"
#include "skerry/lidar_aerial/lidar_aerial_frontend.h"
#include "skerry/sim/aerial_render.h"
#include "skerry/sim/lidar_scans.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/pipeline.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;

// Prior work's second run (a hard left turn into the port, GNSS drifting by metres), cut to 50 s.
std::string MakeDataset(const std::string& name,
                        double duration_s = 50.0,
                        const std::string& scenario = "harbour-lidar-enter-turn-drift",
                        uint64_t seed = 1) {
  sim::ScenarioConfig sc = sim::LoadScenario(scenario);
  sc.duration_s = duration_s;
  const std::string dir = std::string(SKERRY_TEST_TMP_DIR) + "/" + name;
  fs::remove_all(dir);
  Dataset data = sim::Simulate(sc, seed);
  sim::RenderAerialImage(sc, seed, &data, dir);
  sim::RenderLidarScans(sc, seed, &data, dir);
  WriteDataset(data, dir);
  return dir;
}

size_t SensorIndex(const SensorLog& log, const std::string& name) {
  for (size_t k = 0; k < log.sensors.size(); ++k) {
    if (log.sensors[k].name == name) return k;
  }
  ADD_FAILURE() << "no sensor " << name;
  return 0;
}

// Every scan becomes a block, the window takes most of them, and once the vessel has turned into
// the port (the breakwater alone, before, leaves the position along it to the drifting receiver)
// the LiDAR holds the position to decimetres and the heading to a tenth of a degree against a
// receiver drifting by metres (docs/results.md).
TEST(HarbourDataset, ScansBecomeBlocksAndHoldTheEstimate) {
  const Dataset data = LoadDataset(MakeDataset("lidar_ok"));
  ASSERT_EQ(data.lidars.size(), 1u);
  const size_t scans = data.lidar_scans[0].size();
  ASSERT_GE(scans, 45u);
  const EstimatorConfig config = LoadPreset("lidar-harbour");
  // The preset's window spans ten of the 1 Hz scans, so each is re-solved against the next nine
  // before it is marginalised (a 1 s window held one: the tour's error 0.68 m against 0.47 m,
  // docs/results.md "The window against the best causal estimate").
  EXPECT_GE(config.window_keyframes / config.keyframe_rate_hz, 10.0 - 1e-9);
  const SensorLog log = DatasetSensors(data, config);
  ASSERT_EQ(log.frontend_stats.at("lidar").at("blocks"), static_cast<double>(scans));
  const WindowRun run = RunWindow(data, config, {}, nullptr, log);
  ASSERT_FALSE(run.diverged);
  const size_t lidar = SensorIndex(run.sensors, "lidar");
  const SensorStats& st = run.sensor_stats.at(lidar);
  EXPECT_GE(st.accepted, static_cast<int>(0.8 * scans)) << st.rejected << " rejected";
  // The receiver drifts by metres and the window's drift state follows it, so its fixes pass the
  // gate (while the window started each new keyframe's drift at zero, 98 % were refused).
  EXPECT_GE(run.gnss.accepted, static_cast<int>(0.9 * data.gnss_fixes.size()))
      << run.gnss.rejected << " rejected";
  const std::map<std::string, double>& fe = run.sensors.frontend_stats.at("lidar");
  EXPECT_GT(fe.at("median_edge_points"), 100.0);
  EXPECT_EQ(fe.at("skipped_no_returns"), 0.0);
  EXPECT_EQ(fe.at("without_point_times"), 0.0);
  // Per scan (the run folder's blocks.csv): a row for every scan, its flag where its block was
  // made, the flags summing to summary.json's count, and every block the window decided on has
  // its row.
  const FrontendBlockTable table = run.sensors.live_frontend_blocks.at("lidar")();
  ASSERT_EQ(table.rows.size(), scans);
  const auto column = [&table](const std::string& name) {
    const auto it = std::find(table.columns.begin(), table.columns.end(), name);
    EXPECT_NE(it, table.columns.end()) << name;
    return static_cast<size_t>(it - table.columns.begin());
  };
  const size_t made = column("made"), flag = column("degenerate"),
               ratio = column("constraint_ratio"), weak = column("weak_direction_deg"),
               edges = column("edge_points");
  int degenerate = 0, degenerate_early = 0;
  for (const auto& [t, row] : table.rows) {
    ASSERT_EQ(row.size(), table.columns.size());
    EXPECT_GT(row[edges], 0.0);
    if (row[made] == 0.0) {
      EXPECT_TRUE(std::isnan(row[flag]) && std::isnan(row[ratio]) && std::isnan(row[weak]));
      continue;
    }
    EXPECT_GE(row[ratio], 0.0);
    EXPECT_LE(row[ratio], 1.0);
    EXPECT_GE(row[weak], 0.0);
    EXPECT_LT(row[weak], 180.0);
    EXPECT_EQ(row[flag], row[ratio] < lidar_aerial::kDegenerateConstraintRatio ? 1.0 : 0.0);
    degenerate += static_cast<int>(row[flag]);
    degenerate_early += static_cast<int>(row[flag]) * (NsToSeconds(t) < 20.0);
  }
  EXPECT_EQ(degenerate, fe.at("degenerate_scans"));
  for (const SensorRecord& d : run.sensors.decisions) {
    if (d.sensor == static_cast<SensorId>(lidar) && d.decision != SensorDecision::kDropped) {
      EXPECT_EQ(table.rows.count(d.t_ns), 1u) << NsToSeconds(d.t_ns);
    }
  }
  std::printf("%d degenerate scans, %d of them in the first 20 s (the breakwater alone)\n",
              degenerate, degenerate_early);
  // The flag is raised where the breakwater alone is in view (24 scans, 20 of them there).
  EXPECT_GT(degenerate_early, degenerate / 2);
  EXPECT_GE(degenerate_early, 5);
  const EvaluationResult ev = Evaluate(run.records, data.groundtruth);
  double h2 = 0.0, psi2 = 0.0, nees = 0.0;
  int n = 0, n_breakwater = 0;
  for (const EpochError& e : ev.epochs) {
    // Along the breakwater the position along it is the drifting receiver's, metres off; the
    // window must say so (information_at_scale.h): the scans' local curvature claimed decimetres
    // there (horizontal NEES 35 on average over these 20 s, now 7; 2 is consistent).
    if (NsToSeconds(e.t_ns) < 20.0 && e.has_nees) {
      nees += e.nees_horizontal;
      ++n_breakwater;
    }
    if (NsToSeconds(e.t_ns) < 30.0) continue;  // through the entrance
    h2 += e.p_err_w.head<2>().squaredNorm();
    psi2 += e.heading_err_deg * e.heading_err_deg;
    ++n;
  }
  ASSERT_GT(n, 50);                   // keyframes at 2 Hz (the preset) after 30 s of a 60 s run
  EXPECT_LT(std::sqrt(h2 / n), 0.5);  // 0.31 m (0.30 on local curvature; a 1 s window 0.33 m)
  EXPECT_LT(std::sqrt(psi2 / n), 0.2);
  ASSERT_GT(n_breakwater, 20);
  EXPECT_LT(nees / n_breakwater, 12.0);
  std::printf(
      "after 30 s: horizontal RMSE %.3f m, heading RMSE %.3f deg; horizontal NEES %.2f over the "
      "first 20 s\n",
      std::sqrt(h2 / n), std::sqrt(psi2 / n), nees / n_breakwater);
}

// The largest horizontal distance between two runs' estimates at the same instants from t0_s on.
double LargestDistanceFrom(const WindowRun& a, const WindowRun& b, double t0_s) {
  std::map<TimeNs, Eigen::Vector3d> other;
  for (const EstimateRecord& r : b.records) other[r.state.t_ns] = r.state.p_w_b;
  double worst = 0.0;
  for (const EstimateRecord& r : a.records) {
    const auto it = other.find(r.state.t_ns);
    if (NsToSeconds(r.state.t_ns) < t0_s || it == other.end()) continue;
    worst = std::max(worst, (r.state.p_w_b - it->second).head<2>().norm());
  }
  return worst;
}

// The map in tiles (lidar_aerial.map_tile_above_mcells 0: tiles whatever the box; 100 m squares,
// so that the 50 s of the turn cross several) holds the estimate as one map of the track's box
// does: every block is made on the tile at its body's position, and the two runs stay within
// decimetres of each other (their edges come from each tile's own thresholds, so not to the bit).
TEST(HarbourDataset, ATiledMapHoldsTheEstimateAsOneMapDoes) {
  const Dataset data = LoadDataset(MakeDataset("lidar_tiles"));
  const EstimatorConfig whole_config = LoadPreset("lidar-harbour");
  EstimatorConfig tiled_config = whole_config;
  tiled_config.lidar_aerial.map_tile_above_mcells = 0.0;
  tiled_config.lidar_aerial.map_tile_m = 100.0;
  const WindowRun whole =
      RunWindow(data, whole_config, {}, nullptr, DatasetSensors(data, whole_config));
  const WindowRun tiled =
      RunWindow(data, tiled_config, {}, nullptr, DatasetSensors(data, tiled_config));
  ASSERT_FALSE(whole.diverged);
  ASSERT_FALSE(tiled.diverged);
  const std::map<std::string, double>& fw = whole.sensors.frontend_stats.at("lidar");
  const std::map<std::string, double>& ft = tiled.sensors.frontend_stats.at("lidar");
  EXPECT_EQ(fw.at("map_tiles"), 0.0);
  EXPECT_GE(ft.at("map_tiles"), 2.0);
  EXPECT_GT(ft.at("map_s"), 0.0);
  EXPECT_EQ(ft.at("skipped_off_map"), fw.at("skipped_off_map"));
  const size_t lidar = SensorIndex(tiled.sensors, "lidar");
  EXPECT_GE(tiled.sensor_stats.at(lidar).accepted,
            whole.sensor_stats.at(SensorIndex(whole.sensors, "lidar")).accepted - 3);
  const auto rmse_after = [&data](const WindowRun& run, double t0_s) {
    const EvaluationResult ev = Evaluate(run.records, data.groundtruth);
    double h2 = 0.0;
    int n = 0;
    for (const EpochError& e : ev.epochs) {
      if (NsToSeconds(e.t_ns) < t0_s) continue;
      h2 += e.p_err_w.head<2>().squaredNorm();
      ++n;
    }
    return n > 0 ? std::sqrt(h2 / n) : std::numeric_limits<double>::infinity();
  };
  const double apart = LargestDistanceFrom(tiled, whole, 30.0);
  std::printf(
      "after 30 s: horizontal RMSE %.3f m (tiles, %.0f made) against %.3f m (one map); "
      "at most %.3f m apart\n",
      rmse_after(tiled, 30.0), ft.at("map_tiles"), rmse_after(whole, 30.0), apart);
  EXPECT_LT(rmse_after(tiled, 30.0), 0.5);
  EXPECT_LT(apart, 0.3);
}

// Prior work's second run with its 14.5 m jump for 20 s from 25 s, cut to 50 s, beside its twin
// without the jump (the same truth and noise: the fixes differ only while the jump is on). The
// lidar-harbour preset takes the jump into the receiver's drift as a step once it has explained
// a second of fixes (gnss.jump_as_drift_step) and keeps the fixes after it: the jump then moves
// the estimate by 0.31 m at most against 0.58 m when its 20 s of fixes are refused (in the turn,
// where the twin without the jump follows a swing of its receiver that the refusing window never
// hears; docs/results.md). Fixes taken against the stepped drift are marked across_jump, and the
// batch, which models no steps, leaves them out.
TEST(HarbourDataset, AJumpIsCarriedInTheReceiversDrift) {
  const Dataset drift = LoadDataset(MakeDataset("lidar_jump_twin", 50.0));
  const Dataset jump =
      LoadDataset(MakeDataset("lidar_jump", 50.0, "harbour-lidar-enter-turn-jump"));
  const sim::ScenarioConfig sc = sim::LoadScenario("harbour-lidar-enter-turn-jump");
  ASSERT_EQ(sc.gnss.jumps.size(), 1u);
  const double t0 = sc.gnss.jumps[0].start_s, t1 = t0 + sc.gnss.jumps[0].duration_s;
  ASSERT_LT(t1 + 2.0, 50.0);
  EstimatorConfig config = LoadPreset("lidar-harbour");
  ASSERT_TRUE(config.gnss_jump_as_drift_step);
  const auto run = [&](const Dataset& data, const EstimatorConfig& c) {
    WindowRun r = RunWindow(data, c, {}, nullptr, DatasetSensors(data, c));
    EXPECT_FALSE(r.diverged) << r.failure;
    return r;
  };
  const WindowRun twin = run(drift, config);
  const WindowRun stepped = run(jump, config);
  EXPECT_EQ(stepped.gnss.drift_steps, 2);  // the jump, and the receiver back
  int jumped = 0, across = 0, across_outside = 0, refused = 0;
  for (size_t k = 0; k < stepped.decisions.size(); ++k) {
    const double t = NsToSeconds(stepped.decisions[k].t_ns);
    const bool on = t >= t0 && t < t1;
    jumped += on;
    across += on && stepped.decisions[k].across_jump;
    across_outside += !on && stepped.decisions[k].across_jump;
    refused += stepped.decisions[k].position == FixDecision::kRejectedByGate;
  }
  ASSERT_GT(jumped, 150);
  EXPECT_GE(across, jumped - 15) << "the jump's fixes after its first second are taken";
  EXPECT_EQ(across_outside, 0);
  EXPECT_LE(refused, 30);  // a second at each step (22 here)
  const double pull = LargestDistanceFrom(stepped, twin, t0);
  config.gnss_jump_as_drift_step = false;
  const WindowRun refusing = run(jump, config);
  EXPECT_EQ(refusing.gnss.drift_steps, 0);
  const double pull_refusing = LargestDistanceFrom(refusing, twin, t0);
  EXPECT_LT(pull, 0.5);  // issue 12's target
  EXPECT_LT(pull, pull_refusing);
  std::printf("the jump's pull: %.2f m carried in the drift, %.2f m refused\n", pull,
              pull_refusing);
  // The batch gets none of the fixes taken across the jump.
  config.gnss_jump_as_drift_step = true;
  const BatchResult batch =
      SmoothBatch(jump, config, stepped.records, stepped.decisions, stepped.sensors);
  ASSERT_TRUE(batch.usable);
  int taken = 0;
  for (const FixRecord& d : stepped.decisions) {
    taken += d.position != FixDecision::kRejectedByGate && d.position != FixDecision::kDropped &&
             !d.across_jump;
  }
  EXPECT_EQ(batch.gnss_used + batch.gnss_rejected_after_solve, taken);
}

// The batch's covariances with the LiDAR holding the position to centimetres beside a GNSS drift
// state of metres: the information-form pivots of the chain recursion came out indefinite there
// (prior work's first run: negative north variances from 42 s on, which `skerry evaluate`
// refused), and the recursion now falls back to its square-root form (NavGraph::AllCovariances).
TEST(HarbourDataset, TheBatchsCovariancesArePositiveSemiDefinite) {
  const Dataset data =
      LoadDataset(MakeDataset("lidar_batch", 60.0, "harbour-lidar-enter-starboard-drift"));
  const EstimatorConfig config = LoadPreset("lidar-harbour");
  const SensorLog log = DatasetSensors(data, config);
  const WindowRun run = RunWindow(data, config, {}, nullptr, log);
  ASSERT_FALSE(run.diverged);
  const BatchResult batch = SmoothUntil(data, config, run, std::numeric_limits<TimeNs>::max());
  ASSERT_TRUE(batch.usable);
  ASSERT_GT(batch.records.size(), 100u);  // 2 Hz and a keyframe at each scan, 60 s
  // The batch's decision per block (skerry smooth's blocks.csv; the LiDAR's scans and the water
  // surface's heights): one per block, in time order, counted per sensor as summary.json counts
  // them, each accepted one inside its gate at its last evaluation and each rejected one outside.
  ASSERT_EQ(batch.sensor_decisions.size(), log.measurements.size());
  const size_t sensors = log.sensors.size();
  std::vector<int> accepted(sensors, 0), rejected(sensors, 0);
  for (size_t i = 0; i < batch.sensor_decisions.size(); ++i) {
    const SensorRecord& d = batch.sensor_decisions[i];
    if (i > 0) {
      EXPECT_GE(d.t_ns, batch.sensor_decisions[i - 1].t_ns);
    }
    if (d.decision == SensorDecision::kDropped) continue;
    ++(d.decision == SensorDecision::kAccepted ? accepted : rejected).at(d.sensor);
    ASSERT_GT(d.dim, 0);
    const double p = log.sensors.at(d.sensor).gate_probability;
    if (!(p > 0.0)) continue;
    const double gate = ChiSquareQuantile(p, d.dim);
    if (d.decision == SensorDecision::kAccepted) {
      EXPECT_LE(d.d2, gate) << i;
    }
    if (d.decision == SensorDecision::kRejectedByGate) {
      EXPECT_GT(d.d2, gate) << i;
    }
  }
  EXPECT_EQ(accepted, batch.sensor_used);
  EXPECT_EQ(rejected, batch.sensor_rejected_after_solve);
  int scans = 0;
  for (size_t k = 0; k < sensors; ++k) scans += log.sensors[k].name == "lidar" ? accepted[k] : 0;
  EXPECT_GT(scans, 50);  // of 60
  int without = 0, indefinite = 0;
  double worst = 0.0;
  for (const EstimateRecord& r : batch.records) {
    if (!r.has_covariance) {
      ++without;
      continue;
    }
    const double lowest =
        Eigen::SelfAdjointEigenSolver<StateCovariance>(r.covariance).eigenvalues()(0);
    const double scale = r.covariance.diagonal().maxCoeff();
    worst = std::min(worst, lowest / scale);
    indefinite += lowest < -1e-9 * scale;
  }
  EXPECT_EQ(without, 0);
  EXPECT_EQ(indefinite, 0) << "lowest eigenvalue over the largest variance: " << worst;
}

// At rest no course over ground gives a heading and a MEMS gyro cannot find north: the first scan
// registered on its own, the heading searched all round, starts the window (init.mode auto without
// a dual-antenna heading; docs/lidar_aerial.md, *Start*). Around a receiver 300 m off, init.mode
// lidar finds nothing and says so; auto then starts from the receiver as before.
TEST(HarbourDataset, AVesselAtRestStartsFromItsFirstScan) {
  const Dataset data =
      LoadDataset(MakeDataset("lidar_rest", 12.0, "harbour-lidar-stationary-drift"));
  EstimatorConfig config = LoadPreset("lidar-harbour");
  ASSERT_EQ(config.init.mode, "auto");
  const SensorLog log = DatasetSensors(data, config);
  ASSERT_TRUE(log.start.has_value());
  const NavState& start = log.start->state;
  const auto truth =
      std::lower_bound(data.truth_states.begin(), data.truth_states.end(), start.t_ns,
                       [](const NavState& s, TimeNs t) { return s.t_ns < t; });
  ASSERT_NE(truth, data.truth_states.end());
  EXPECT_LT((start.p_w_b - truth->p_w_b).head<2>().norm(), 1.0);
  const double yaw_err = std::remainder(HeadingDeg(start.q_w_b) - HeadingDeg(truth->q_w_b), 360.0);
  EXPECT_LT(std::abs(yaw_err), 1.5);
  EXPECT_LT(std::sqrt(log.start->covariance(kRot + 2, kRot + 2)) * 180.0 / M_PI, 2.0);

  Dataset far = data;
  for (GnssFix& f : far.gnss_fixes) f.p_w.x() += 300.0;
  config.init.mode = "lidar";
  try {
    DatasetSensors(far, config);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("init.mode lidar"), std::string::npos) << e.what();
  }
  config.init.mode = "auto";
  EXPECT_FALSE(DatasetSensors(far, config).start.has_value());
}

// A first scan that matches a repetitive harbour nearly as well 14 m north of where the vessel
// is (prior work's first run, seed 12: the second-best match 0.90 of the best, just inside the
// ambiguity test) must not start the window while the receiver says otherwise. Measured before
// the start was tested against the receiver's fix: the window started 11.9 m off with a 0.34 m
// sigma, refused the receiver, and was 91 m off within 20 s (and seed 11, 11.8 m at the start,
// took 15 s to come back); now the scan is not taken (chi-square 29 against 13.8) and the
// window starts from the receiver.
TEST(HarbourDataset, AStartTheReceiverContradictsIsNotTaken) {
  const Dataset data = LoadDataset(
      MakeDataset("lidar_ambiguous_start", 30.0, "harbour-lidar-enter-starboard-drift", 12));
  const EstimatorConfig config = LoadPreset("lidar-harbour");
  const SensorLog log = DatasetSensors(data, config);
  if (log.start) {
    const auto truth =
        std::lower_bound(data.truth_states.begin(), data.truth_states.end(), log.start->state.t_ns,
                         [](const NavState& s, TimeNs t) { return s.t_ns < t; });
    ASSERT_NE(truth, data.truth_states.end());
    EXPECT_LT((log.start->state.p_w_b - truth->p_w_b).head<2>().norm(), 2.0);
  }
  const WindowRun run = RunWindow(data, config, {}, nullptr, log);
  ASSERT_FALSE(run.diverged) << run.failure;
  double worst = 0.0;
  for (const EpochError& e : Evaluate(run.records, data.groundtruth).epochs) {
    worst = std::max(worst, e.p_err_w.head<2>().norm());
  }
  std::printf("seed 12: %s, worst horizontal error over 30 s %.2f m\n",
              log.start ? "started from a scan" : "no scan taken as the start", worst);
  EXPECT_LT(worst, 5.0);
}

TEST(HarbourDataset, BadInputNamesTheFile) {
  const std::string dir = MakeDataset("lidar_bad", 8.0);
  const EstimatorConfig config = LoadPreset("lidar-harbour");
  Dataset data = LoadDataset(dir);
  // A LiDAR without an aerial image to align to.
  Dataset no_map = data;
  no_map.orthophoto.reset();
  try {
    DatasetSensors(no_map, config);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("orthophoto"), std::string::npos) << e.what();
  }
  // A scan cut short.
  const std::string scan =
      (fs::path(data.lidars[0].scan_dir) / data.lidar_scans[0].at(2).file).string();
  fs::resize_file(scan, fs::file_size(scan) / 2);
  try {
    DatasetSensors(data, config);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(scan), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace skerry
