// End to end through the real `skerry` binary: simulate -> run / smooth -> evaluate on a short
// harbour scenario, and bad input that must exit with status 2 and name the file, line and
// field on stderr (docs/dataset-format.md, "Errors").

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli_test_util.h"
#include "core/test_util.h"
#include "skerry/eval/evaluation.h"
#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/io/trajectory.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/pipeline.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::FreshDir;
using testing::Quote;
using testing::ReadLines;
using testing::ReadText;
using testing::RunCli;
using testing::ShortScenarioYaml;
using testing::UnbudgetedConfig;
using testing::WriteLines;
using testing::WriteText;

/// A simulated dataset of the short harbour scenario, written by `skerry simulate`.
std::string MakeDataset(const std::string& name, double duration_s, int seed = 4) {
  const std::string dir = FreshDir(name);
  const std::string scenario = dir + "/scenario.yaml";
  WriteText(scenario, ShortScenarioYaml(duration_s));
  const std::string data = dir + "/data";
  const CliResult r = RunCli("simulate --scenario " + Quote(scenario) + " --seed " +
                             std::to_string(seed) + " --out " + Quote(data));
  EXPECT_EQ(r.status, 0) << r.err;
  return data;
}

nlohmann::json ReadJson(const std::string& path) {
  return nlohmann::json::parse(ReadText(path), nullptr, /*allow_exceptions=*/false);
}

size_t CountDataLines(const std::string& path, char comment = '\0') {
  size_t n = 0;
  for (const std::string& line : ReadLines(path)) {
    if (line.empty() || (comment != '\0' && line[0] == comment)) continue;
    ++n;
  }
  return n;
}

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream s(line);
  for (std::string f; std::getline(s, f, ',');) fields.push_back(f);
  return fields;
}

// `skerry COMMAND --dataset DATA` without the per-solve time budget (a loaded machine can cut a
// budgeted solve in one run and not the other), quietly: once on one thread into DIR/one, once
// with `jobs` (e.g. "-j 2") into DIR. True when both exit with status 0.
bool RunOnOneThreadAndOnMore(const std::string& command,
                             const std::string& data,
                             const std::string& dir,
                             const std::string& jobs) {
  const std::string base =
      command + " --dataset " + Quote(data) + " --config " + Quote(UnbudgetedConfig(dir)) + " -q";
  const CliResult one = RunCli(base + " --out " + Quote(dir + "/one"));
  const CliResult more = RunCli(base + " " + jobs + " --out " + Quote(dir));
  EXPECT_EQ(one.status, 0) << one.err;
  EXPECT_EQ(more.status, 0) << more.err;
  return one.status == 0 && more.status == 0;
}

std::string Join(const std::vector<std::string>& fields) {
  std::string out;
  for (size_t k = 0; k < fields.size(); ++k) out += (k ? "," : "") + fields[k];
  return out;
}

// ----------------------------------------------------------------------------------------------

// --earth and --matched change the world simulated, and the dataset's name says so.
TEST(CliTest, SimulateNamesAnotherWorld) {
  const std::string dir = FreshDir("sim-worlds");
  ASSERT_EQ(RunCli("simulate --scenario harbour --earth flat --out " + Quote(dir + "/flat")).status,
            0);
  const Dataset flat = LoadDataset(dir + "/flat");
  EXPECT_EQ(flat.name, "harbour-flat");
  EXPECT_EQ(flat.earth.kind, EarthKind::kFlat);
  ASSERT_EQ(
      RunCli("simulate --scenario harbour --earth wgs84 --matched --out " + Quote(dir + "/matched"))
          .status,
      0);
  const Dataset matched = LoadDataset(dir + "/matched");
  EXPECT_EQ(matched.name, "harbour-matched");  // wgs84 is the scenario's own world
  EXPECT_EQ(matched.earth.kind, EarthKind::kWgs84);
  // A DEM's error needs a DEM: the harbour has none.
  const CliResult no_dem =
      RunCli("simulate --scenario harbour --dem-error 4 --out " + Quote(dir + "/dem"));
  EXPECT_NE(no_dem.status, 0);
  EXPECT_NE(no_dem.err.find("--dem-error: the scenario has no dem"), std::string::npos)
      << no_dem.err;
  EXPECT_NE(
      RunCli("simulate --scenario harbour --dem-error -1 --out " + Quote(dir + "/dem")).status, 0);
  // A seed that is not one: refused, naming the option, where CLI11 alone made -5 "not given"
  // (the scenario's own seed) and a seed past 2^64 the largest integer, both silently.
  for (const char* bad : {"-5", "18446744073709551616", "99999999999999999999", "1.5", "x"}) {
    const CliResult r = RunCli(std::string("simulate --scenario harbour --seed ") + bad +
                               " --out " + Quote(dir + "/seed"));
    EXPECT_EQ(r.status, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find("--seed"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("must be a whole number from 0 to 18446744073709551615"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/seed")) << bad;
  }
}

TEST(CliTest, SimulateWritesADatasetThatLoads) {
  const std::string out = FreshDir("sim") + "/harbour";
  const CliResult r = RunCli("simulate --scenario harbour --seed 3 --out " + Quote(out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("seed 3"), std::string::npos) << r.out;
  const Dataset d = LoadDataset(out);
  EXPECT_EQ(d.name, "harbour");
  // 600 s at 200 Hz; 2 Hz GNSS less the 120 s outage; 50 Hz ground truth.
  EXPECT_NEAR(static_cast<double>(d.imu_samples.size()), 600.0 * 200.0, 2.0);
  EXPECT_NEAR(static_cast<double>(d.gnss_fixes.size()), (600.0 - 120.0) * 2.0, 3.0);
  EXPECT_NEAR(static_cast<double>(d.groundtruth.size()), 600.0 * 50.0, 2.0);
  EXPECT_EQ(d.truth_states.size(), d.groundtruth.size());
  ASSERT_EQ(d.events.size(), 2u);
  EXPECT_TRUE(d.has_gnss);
  EXPECT_NEAR(d.origin.lat_deg, 47.60, 1e-12);
  EXPECT_NEAR(d.origin.lon_deg, 9.45, 1e-12);
  // The extrinsics of the scenario survive the round trip through dataset.yaml.
  EXPECT_NEAR((d.imu.p_b_i - Eigen::Vector3d(1.2, -0.3, 0.5)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((d.gnss.p_b_g - Eigen::Vector3d(-1.5, 0.0, 2.8)).norm(), 0.0, 1e-12);
  // Fixes sit near the truth: the antenna's true position within a few sigma.
  const GnssFix& fix = d.gnss_fixes[100];
  StampedPose truth;
  ASSERT_TRUE(InterpolatePose(d.groundtruth, fix.t_ns, &truth));
  const Eigen::Vector3d antenna = truth.p_w_b + truth.q_w_b * d.gnss.p_b_g;
  EXPECT_LT((fix.p_w - antenna).head<2>().norm(), 3.0);
}

TEST(CliTest, RunThenEvaluate) {
  const std::string data = MakeDataset("data", 90.0);
  const std::string out = FreshDir("run");
  const CliResult r = RunCli("run --dataset " + Quote(data) + " --out " + Quote(out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("horizontal RMSE"), std::string::npos) << r.out;
  for (const char* f : {"trajectory.tum", "states.csv", "covariances.csv", "summary.json"}) {
    EXPECT_TRUE(fs::is_regular_file(out + "/" + f)) << f;
  }
  const nlohmann::json s = ReadJson(out + "/summary.json");
  ASSERT_FALSE(s.is_discarded()) << "summary.json does not parse";
  for (const char* key : {"command", "dataset", "configuration", "solver", "timing", "accuracy"}) {
    EXPECT_TRUE(s.contains(key)) << key;
  }
  EXPECT_EQ(s.value("command", ""), "run");
  EXPECT_EQ(s["configuration"].value("name", ""), "default");
  EXPECT_EQ(s["dataset"].value("name", ""), "harbour-short");
  // The window's wall time holds the streamed reads and the writes as it went; the load (of
  // what is not streamed), the writes and the evaluation are also said on their own.
  const nlohmann::json& timing = s["timing"];
  for (const char* key : {"wall_s", "load_s", "write_s", "evaluate_s", "total_s"}) {
    ASSERT_TRUE(timing.contains(key) && timing[key].is_number()) << key;
    EXPECT_GT(timing[key].get<double>(), 0.0) << key;
  }
  EXPECT_LE(timing["load_s"].get<double>() + timing["wall_s"].get<double>() +
                timing["evaluate_s"].get<double>(),
            timing["total_s"].get<double>() + 1e-6)
      << timing.dump();
  EXPECT_LE(timing["write_s"].get<double>(), timing["total_s"].get<double>()) << timing.dump();
  ASSERT_TRUE(s["accuracy"].is_object());
  const double rmse = s["accuracy"]["horizontal_m"]["rmse"].get<double>();
  EXPECT_TRUE(std::isfinite(rmse));
  EXPECT_GT(rmse, 0.0);
  EXPECT_LT(rmse, 2.0) << "window horizontal RMSE, m";

  // One line per keyframe in every output; 10 Hz over 90 s.
  const size_t keyframes = s["solver"]["keyframes"].get<size_t>();
  EXPECT_NEAR(static_cast<double>(keyframes), 900.0, 40.0);
  EXPECT_EQ(CountDataLines(out + "/states.csv"), keyframes + 1);
  EXPECT_EQ(CountDataLines(out + "/covariances.csv"), keyframes + 1);
  EXPECT_EQ(CountDataLines(out + "/trajectory.tum", '#'), keyframes);
  const std::vector<EstimateRecord> est =
      ReadEstimate(out + "/states.csv", out + "/covariances.csv");
  ASSERT_EQ(est.size(), keyframes);
  EXPECT_TRUE(est.back().has_covariance);
  EXPECT_EQ(s["dataset"]["imu_samples"].get<size_t>(), LoadDataset(data).imu_samples.size());

  // --jobs: a camera's frames on more threads (skyline.threads; the estimate on camera data
  // the same to the last bit: SkylineDataset.SimulatedFramesBecomeBlocksAndTheWindowTakesThem).
  // Compared without the per-solve time budget, which a loaded machine could hit in one run and
  // not in the other.
  const std::string out2 = FreshDir("run_jobs");
  ASSERT_TRUE(RunOnOneThreadAndOnMore("run", data, out2, "-j 2"));
  EXPECT_EQ(ReadText(out2 + "/states.csv"), ReadText(out2 + "/one/states.csv"));
  const std::string configuration = ReadJson(out2 + "/summary.json")["configuration"].dump();
  EXPECT_NE(configuration.find("\\n  threads: 2\\n"), std::string::npos) << configuration;
  for (const char* bad : {"0", "-1", "257", "two"}) {
    const CliResult j = RunCli("run --dataset " + Quote(data) + " --jobs " + bad + " --out " +
                               Quote(out2 + "_bad"));
    EXPECT_EQ(j.status, 2) << bad << ": " << j.err;
    EXPECT_NE(j.err.find("--jobs"), std::string::npos) << j.err;
  }

  // --set: keys of the preset changed, the others the preset's (docs/configuration.md).
  const std::string out3 = FreshDir("run_set");
  const CliResult set = RunCli("run --dataset " + Quote(data) + " --set window_keyframes=7 " +
                               "--set solver.max_iterations=3 --out " + Quote(out3) + " -q");
  ASSERT_EQ(set.status, 0) << set.err;
  const nlohmann::json set_config = ReadJson(out3 + "/summary.json")["configuration"];
  EXPECT_EQ(set_config.value("name", ""), "default");
  WriteText(out3 + "/read_back.yaml", set_config.value("yaml", ""));
  const EstimatorConfig read_back = LoadEstimatorConfig(out3 + "/read_back.yaml");
  EstimatorConfig expected = LoadPreset("default");
  expected.window_keyframes = 7;
  expected.ceres.max_iterations = 3;
  EXPECT_EQ(ToYaml(read_back), ToYaml(expected));

  // evaluate reads the files back and reports the same horizontal RMSE.
  const std::string json_out = out + "/eval.json";
  const CliResult e =
      RunCli("evaluate --estimate " + Quote(out + "/states.csv") + " --groundtruth " +
             Quote(data + "/groundtruth.tum") + " --json " + Quote(json_out));
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_NE(e.out.find("ATE"), std::string::npos) << e.out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(e.out, m, std::regex("horizontal RMSE ([0-9.]+) m"))) << e.out;
  EXPECT_NEAR(std::stod(m[1]), rmse, 1e-3);
  const nlohmann::json ej = ReadJson(json_out);
  ASSERT_FALSE(ej.is_discarded());
  EXPECT_NEAR(ej["horizontal_m"]["rmse"].get<double>(), rmse, 1e-9);

  // A span (an outage, say): its own figures in the output and the JSON; the whole run as the
  // span gives the whole run's RMSE; a span without estimates is an error naming the file.
  const CliResult sp = RunCli("evaluate --estimate " + Quote(out + "/states.csv") +
                              " --groundtruth " + Quote(data + "/groundtruth.tum") +
                              " --from 0 --to 1000 --edge 20 --json " + Quote(json_out));
  ASSERT_EQ(sp.status, 0) << sp.err;
  EXPECT_NE(sp.out.find("horizontal ANEES"), std::string::npos) << sp.out;
  const nlohmann::json sj = ReadJson(json_out);
  ASSERT_TRUE(sj.contains("span")) << sj.dump();
  EXPECT_NEAR(sj["span"]["horizontal_rmse_m"].get<double>(), rmse, 1e-9);
  EXPECT_EQ(sj["span"]["epochs"].get<size_t>(), keyframes);
  EXPECT_GT(sj["span"]["first_mean_m"].get<double>(), 0.0);
  const CliResult bad =
      RunCli("evaluate --estimate " + Quote(out + "/states.csv") + " --groundtruth " +
             Quote(data + "/groundtruth.tum") + " --from 5000 --to 6000");
  EXPECT_EQ(bad.status, 2) << bad.err;
  EXPECT_NE(bad.err.find("states.csv"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("no estimate between"), std::string::npos) << bad.err;
  // A time that is not one is refused, naming the option: nan was once taken for "not given"
  // (the span from the first estimate), 1e300 came out as a negative time.
  for (const char* given : {"--from nan", "--to 1e300", "--from -inf", "--rpe-delta nan"}) {
    const std::string option = given;
    const CliResult not_a_time =
        RunCli("evaluate --estimate " + Quote(out + "/states.csv") + " --groundtruth " +
               Quote(data + "/groundtruth.tum") + " " + option);
    EXPECT_EQ(not_a_time.status, 2) << option << ": " << not_a_time.err;
    EXPECT_NE(not_a_time.err.find(option.substr(0, option.find(' ')) + ": "), std::string::npos)
        << not_a_time.err;
    EXPECT_NE(not_a_time.err.find("must be a finite"), std::string::npos) << not_a_time.err;
  }

  // And from the TUM trajectory (no covariances): the same positions, the same RMSE.
  const CliResult e2 = RunCli("evaluate --estimate " + Quote(out + "/trajectory.tum") +
                              " --groundtruth " + Quote(data + "/groundtruth.tum"));
  ASSERT_EQ(e2.status, 0) << e2.err;
  ASSERT_TRUE(std::regex_search(e2.out, m, std::regex("horizontal RMSE ([0-9.]+) m"))) << e2.out;
  EXPECT_NEAR(std::stod(m[1]), rmse, 1e-3);
}

// init.mode align from a config file: the run says when the bank decided, in its output and in
// summary.json; without align there is no such section.
// `skerry run` reads imu.csv and gnss.csv as it goes and writes the estimates as they become
// final (a day at sea in flat memory: bench/long_run.sh); what it writes is what the run over the
// dataset loaded whole makes.
TEST(CliTest, RunStreamsItsInputAndWritesWhatTheWholeRunWould) {
  const std::string data = MakeDataset("stream", 60.0);
  const std::string out = FreshDir("streamed");
  const std::string unbudgeted = UnbudgetedConfig(out);
  const CliResult r = RunCli("run --dataset " + Quote(data) + " --config " + Quote(unbudgeted) +
                             " --out " + Quote(out) + " -q");
  ASSERT_EQ(r.status, 0) << r.err;
  const Dataset whole = LoadDataset(data);
  const WindowRun run = RunWindow(whole, LoadPreset(unbudgeted));
  const std::string expected = FreshDir("whole");
  WriteEstimateFiles(expected, run.records);
  for (const char* f : {"/trajectory.tum", "/states.csv", "/covariances.csv"}) {
    EXPECT_EQ(ReadText(out + f), ReadText(expected + f)) << f;
  }
  const nlohmann::json summary = ReadJson(out + "/summary.json");
  EXPECT_EQ(summary["dataset"]["imu_samples"].get<size_t>(), whole.imu_samples.size());
  EXPECT_EQ(summary["dataset"]["gnss_fixes"].get<size_t>(), whole.gnss_fixes.size());
  EXPECT_EQ(summary["solver"]["keyframes"].get<size_t>(), run.records.size());
  EXPECT_NEAR(summary["dataset"]["duration_s"].get<double>(),
              NsToSeconds(whole.imu_samples.back().t_ns - whole.imu_samples.front().t_ns), 1e-9);
  EXPECT_EQ(summary["solver"]["gnss"]["accepted"].get<int>(), run.gnss.accepted);
  EXPECT_NEAR(summary["accuracy"]["horizontal_m"]["rmse"].get<double>(),
              Evaluate(run.records, whole.groundtruth).horizontal.rmse, 1e-12);
}

TEST(CliTest, RunWithAlignReportsTheDecision) {
  const std::string data = MakeDataset("data", 90.0);
  const std::string dir = FreshDir("align");
  const std::string config = dir + "/align.yaml";
  WriteText(config, "init:\n  mode: align\n");
  const std::string out = dir + "/run";
  const CliResult r = RunCli("run --dataset " + Quote(data) + " --config " + Quote(config) +
                             " --out " + Quote(out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("align: decided"), std::string::npos) << r.out;
  const nlohmann::json s = ReadJson(out + "/summary.json");
  ASSERT_TRUE(s.contains("align")) << s.dump();
  const double after = s["align"]["decided_after_s"].get<double>();
  EXPECT_GE(after, 20.0);  // init.align_min_s
  EXPECT_LT(after, 90.0);
  EXPECT_EQ(s["align"]["hypotheses"].get<int>(), 12);
  EXPECT_GT(s["align"]["kept_weight"].get<double>(), 0.0);
  EXPECT_LE(s["align"]["kept_weight"].get<double>(), 1.0);
  EXPECT_TRUE(s["align"]["clear_winner"].get<bool>());
  EXPECT_LT(s["accuracy"]["horizontal_m"]["rmse"].get<double>(), 2.0);

  const std::string plain = dir + "/plain";
  ASSERT_EQ(RunCli("run --dataset " + Quote(data) + " --out " + Quote(plain) + " --quiet").status,
            0);
  EXPECT_FALSE(ReadJson(plain + "/summary.json").contains("align"));
}

// A run the watchdog gives up on is not a result: exit status 3, the reason on stderr, and a
// summary.json that says "diverged" with the watchdog's events, but no estimates. The IMU's gyro
// bias is 0.3 rad/s while dataset.yaml tells the estimator 1e-6.
TEST(CliTest, ADivergedRunIsNotAResult) {
  const std::string dir = FreshDir("diverging");
  std::string yaml = ShortScenarioYaml(400.0);
  const std::string grade = "  grade: tactical";
  yaml.insert(yaml.find(grade) + grade.size(), "\n  gyro_bias_initial_sigma_rad_s: 0.3");
  WriteText(dir + "/scenario.yaml", yaml);
  const std::string data = dir + "/data";
  ASSERT_EQ(RunCli("simulate --scenario " + Quote(dir + "/scenario.yaml") + " --seed 3 --out " +
                   Quote(data))
                .status,
            0);
  std::vector<std::string> lines = ReadLines(data + "/dataset.yaml");
  for (std::string& line : lines) {
    if (line.find("gyro_bias_prior_sigma_rad_s") != std::string::npos) {
      line = "    gyro_bias_prior_sigma_rad_s: 1.0e-6";
    }
  }
  WriteLines(data + "/dataset.yaml", lines);
  const std::string out = FreshDir("diverged_run");
  const CliResult r = RunCli("run --dataset " + Quote(data) + " --out " + Quote(out));
  EXPECT_EQ(r.status, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("diverged"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out + "/states.csv"));
  EXPECT_FALSE(fs::exists(out + "/trajectory.tum"));
  const nlohmann::json summary = ReadJson(out + "/summary.json");
  EXPECT_EQ(summary["status"], "diverged");
  EXPECT_FALSE(summary["failure"].get<std::string>().empty());
  EXPECT_GE(summary["events"].size(), 2u);
  EXPECT_FALSE(summary.contains("accuracy"));
}

TEST(CliTest, Smooth) {
  const std::string data = MakeDataset("data", 90.0);
  const std::string out = FreshDir("smooth");
  const CliResult r =
      RunCli("smooth --dataset " + Quote(data) + " --out " + Quote(out) + " --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(r.out.empty()) << "--quiet printed: " << r.out;
  for (const char* f : {"trajectory.tum", "states.csv", "covariances.csv", "summary.json"}) {
    EXPECT_TRUE(fs::is_regular_file(out + "/" + f)) << f;
  }
  const nlohmann::json s = ReadJson(out + "/summary.json");
  ASSERT_FALSE(s.is_discarded());
  for (const char* key : {"command", "dataset", "configuration", "solver", "timing", "accuracy"}) {
    EXPECT_TRUE(s.contains(key)) << key;
  }
  EXPECT_EQ(s.value("command", ""), "smooth");
  EXPECT_EQ(s.value("status", ""), "ok");  // the initial window's verdict
  EXPECT_TRUE(s["events"].is_array());
  EXPECT_TRUE(s["solver"].value("usable", false));
  const double rmse = s["accuracy"]["horizontal_m"]["rmse"].get<double>();
  const double window_rmse = s["accuracy_window"]["horizontal_m"]["rmse"].get<double>();
  EXPECT_TRUE(std::isfinite(rmse));
  EXPECT_LT(rmse, 2.0);
  // The smoother uses every measurement for every state: no worse than the window.
  EXPECT_LE(rmse, window_rmse + 0.02) << "batch " << rmse << " m, window " << window_rmse << " m";
  const size_t keyframes = s["solver"]["keyframes"].get<size_t>();
  EXPECT_EQ(CountDataLines(out + "/states.csv"), keyframes + 1);
  EXPECT_EQ(CountDataLines(out + "/covariances.csv"), keyframes + 1);
  // The dataset as loaded, though the IMU record and the ground truth go before the batch.
  EXPECT_EQ(s["dataset"].value("imu_samples", size_t{0}), CountDataLines(data + "/imu.csv") - 1);
  EXPECT_NEAR(s["dataset"].value("duration_s", 0.0), 90.0, 0.1);
  EXPECT_TRUE(s["dataset"].value("has_groundtruth", false));
  // Where the time went: the parts are consecutive, inside the whole.
  const nlohmann::json& timing = s["timing"];
  double parts_s = 0.0;
  for (const char* key : {"load_s", "window_s", "batch_s", "write_s", "evaluate_s"}) {
    ASSERT_TRUE(timing.contains(key) && timing[key].is_number()) << key;
    EXPECT_GE(timing[key].get<double>(), 0.0) << key;
    parts_s += timing[key].get<double>();
  }
  EXPECT_GT(timing["load_s"].get<double>(), 0.0);
  EXPECT_GT(timing["write_s"].get<double>(), 0.0);
  for (const char* key : {"batch_solve_s", "covariance_s"}) {
    EXPECT_LE(timing.value(key, 1e9), timing["batch_s"].get<double>()) << key;
  }
  EXPECT_LE(parts_s, timing.value("total_s", 0.0) + 1e-6) << timing.dump();
  EXPECT_NEAR(timing.value("data_s", 0.0), 90.0, 0.1);

  // --jobs: the batch on more threads, the same estimate to the last digit written (without the
  // initial window's per-solve time budget, which a loaded machine could hit in one run only).
  const std::string out3 = FreshDir("smooth_jobs");
  ASSERT_TRUE(RunOnOneThreadAndOnMore("smooth", data, out3, "--jobs 3"));
  EXPECT_EQ(ReadText(out3 + "/states.csv"), ReadText(out3 + "/one/states.csv"));
  EXPECT_EQ(ReadText(out3 + "/covariances.csv"), ReadText(out3 + "/one/covariances.csv"));
  const std::string configuration3 = ReadJson(out3 + "/summary.json")["configuration"].dump();
  EXPECT_NE(configuration3.find("num_threads: 3"), std::string::npos) << configuration3;
  // The initial pass's camera frames too (skyline.threads).
  EXPECT_NE(configuration3.find("\\n  threads: 3\\n"), std::string::npos) << configuration3;
  for (const char* bad : {"0", "-2", "x"}) {
    const CliResult j = RunCli("smooth --dataset " + Quote(data) + " --jobs " + bad + " --out " +
                               Quote(out3 + "_bad"));
    EXPECT_EQ(j.status, 2) << bad << ": " << j.err;
    EXPECT_NE(j.err.find("--jobs"), std::string::npos) << j.err;
  }
}

// `smooth --until T`: the batch over the data up to T alone (DatasetUntil), whose last keyframe is
// the best estimate a live estimator could have made at T (bench/causal_limit.py); a time that
// is not finite is refused, naming the option.
TEST(CliTest, SmoothUntilUsesTheDataUpToThen) {
  const std::string data = MakeDataset("data_until", 60.0);
  const std::string out = FreshDir("smooth_until");
  const CliResult r =
      RunCli("smooth --dataset " + Quote(data) + " --until 35.5 --out " + Quote(out) + " --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> lines = ReadLines(out + "/states.csv");
  ASSERT_GT(lines.size(), 10u);
  std::string last = lines.back();
  for (auto it = lines.rbegin(); last.empty() && it != lines.rend(); ++it) last = *it;
  const double t_last = std::stod(Split(last).at(0));
  EXPECT_LE(t_last, 35.5);
  EXPECT_GT(t_last, 34.5);  // keyframes at 10 Hz up to the end of the data kept
  const nlohmann::json s = ReadJson(out + "/summary.json");
  EXPECT_EQ(s.value("until_s", 0.0), 35.5);
  EXPECT_LT(s["dataset"].value("duration_s", 0.0), 36.0);
  EXPECT_LT(s["dataset"].value("imu_samples", size_t{0}), CountDataLines(data + "/imu.csv") - 1);

  const CliResult bad =
      RunCli("smooth --dataset " + Quote(data) + " --until inf --out " + Quote(out + "_inf"));
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("--until"), std::string::npos) << bad.err;
  for (const char* not_a_time : {"nan", "1e300"}) {
    const CliResult r2 = RunCli("smooth --dataset " + Quote(data) + " --until " + not_a_time +
                                " --out " + Quote(out + "_nan"));
    EXPECT_EQ(r2.status, 2) << not_a_time;
    EXPECT_NE(
        r2.err.find("--until: " + std::string(not_a_time == std::string("nan") ? "nan" : "1e+300") +
                    ": must be a finite time"),
        std::string::npos)
        << r2.err;
  }
  // What CLI11 refuses is bad input too: exit status 2 (it was CLI11's own 105-109).
  EXPECT_EQ(RunCli("smooth --datset " + Quote(data) + " --out " + Quote(out + "_typo")).status, 2);
  EXPECT_EQ(RunCli("evaluate --estimate a --groundtruth b --edge -5").status, 2);
  EXPECT_EQ(RunCli("--help").status, 0);
  const CliResult early =
      RunCli("smooth --dataset " + Quote(data) + " --until -5 --out " + Quote(out + "_early"));
  EXPECT_EQ(early.status, 2);
  EXPECT_NE(early.err.find("--until: leaves no IMU record"), std::string::npos) << early.err;
}

// ----------------------------------------------------------------------------------------------
// Bad input: exit status 2, and stderr names the file, the line and the field.

// A dataset with pose fixes (and GNSS denied after 30 s): `run` and `smooth` take them through
// the frontend seam, summary.json counts each sensor's decisions and reports a calibrated
// extrinsic with its sigmas; a configuration naming a sensor the dataset lacks is refused.
TEST(CliTest, PoseFixesThroughRunAndSmooth) {
  const std::string dir = FreshDir("cli_pose_fixes");
  const std::string scenario = dir + "/scenario.yaml";
  WriteText(scenario, ShortScenarioYaml(90.0, "harbour-pose-fixes",
                                        "  outages:\n    - {start_s: 30, duration_s: 60}\n") +
                          "pose_fixes:\n  rate_hz: 1\n  kind: enh\n"
                          "  outliers: {probability: 0.05}\n"
                          "  T_b_s: {q_xyzw: [0, 0, 0, 1], p_m: [0.5, 0.0, 4.0]}\n");
  const std::string data = dir + "/data";
  ASSERT_EQ(
      RunCli("simulate --scenario " + Quote(scenario) + " --seed 2 --out " + Quote(data)).status,
      0);
  const std::string config = dir + "/calibrate.yaml";
  WriteText(config, "name: calibrate\nsensors:\n  pose_fixes: {calibrate: true}\n");
  const std::string out = dir + "/run";
  const CliResult r = RunCli("run --dataset " + Quote(data) + " --config " + Quote(config) +
                             " --out " + Quote(out) + " --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json summary = ReadJson(out + "/summary.json");
  const nlohmann::json& pf = summary["solver"]["sensors"]["pose_fixes"];
  ASSERT_TRUE(pf.is_object()) << summary["solver"].dump();
  EXPECT_EQ(pf["blocks"].get<int>(), 90);
  EXPECT_GE(pf["rejected_by_gate"].get<int>(), 1);  // 5 % gross
  EXPECT_EQ(
      pf["accepted"].get<int>() + pf["rejected_by_gate"].get<int>() + pf["dropped"].get<int>(), 90);
  const nlohmann::json& x = summary["extrinsics"]["pose_fixes"];
  ASSERT_TRUE(x.is_object()) << summary.dump();
  EXPECT_TRUE(x["sigma_p_m"].is_array());
  EXPECT_LT(x["translation_from_prior_m"].get<double>(), 0.3);

  const std::string smoothed = dir + "/smooth";
  ASSERT_EQ(
      RunCli("smooth --dataset " + Quote(data) + " --out " + Quote(smoothed) + " --quiet").status,
      0);
  const nlohmann::json s2 = ReadJson(smoothed + "/summary.json");
  const nlohmann::json& used = s2["solver"]["sensors"]["pose_fixes"];
  EXPECT_GE(used["used"].get<int>(), 80);
  // The batch's decision per block, in time order, counted as summary.json counts them.
  const std::vector<std::string> rows = ReadLines(smoothed + "/blocks.csv");
  ASSERT_EQ(rows.size(), 91u);
  EXPECT_EQ(rows[0].rfind("t,sensor,decision,reacquired,dim,d2", 0), 0u) << rows[0];
  std::map<std::string, int> decisions;
  double last_t = -1.0;
  for (size_t i = 1; i < rows.size(); ++i) {
    std::stringstream row(rows[i]);
    std::string t, sensor, decision;
    std::getline(row, t, ',');
    std::getline(row, sensor, ',');
    std::getline(row, decision, ',');
    EXPECT_EQ(sensor, "pose_fixes");
    EXPECT_GE(std::stod(t), last_t) << rows[i];
    last_t = std::stod(t);
    ++decisions[decision];
  }
  EXPECT_EQ(decisions["accepted"], used["used"].get<int>());
  EXPECT_EQ(decisions["rejected"], used["rejected_after_solve"].get<int>());
  EXPECT_GE(decisions["rejected"], 1);  // 5 % gross
  EXPECT_EQ(decisions["accepted"] + decisions["rejected"] + decisions["dropped"], 90);

  const std::string wrong = dir + "/wrong.yaml";
  WriteText(wrong, "name: wrong\nsensors:\n  camera: {gate_probability: 0.99}\n");
  const CliResult e = RunCli("run --dataset " + Quote(data) + " --config " + Quote(wrong) +
                             " --out " + Quote(dir + "/wrong"));
  EXPECT_EQ(e.status, 2);
  EXPECT_NE(e.err.find("sensors"), std::string::npos) << e.err;
  EXPECT_NE(e.err.find("camera"), std::string::npos) << e.err;
}

class CliBadInputTest : public ::testing::Test {
 protected:
  void SetUp() override { data_ = MakeDataset("good", 20.0); }

  /// `skerry run` on the (edited) dataset; expects exit 2 and every fragment on stderr.
  void ExpectRunFails(const std::vector<std::string>& fragments,
                      const std::string& extra_args = "") {
    const std::string out = FreshDir("out");
    const CliResult r =
        RunCli("run --dataset " + Quote(data_) + " --out " + Quote(out) + " " + extra_args);
    EXPECT_EQ(r.status, 2) << "stderr: " << r.err;
    for (const std::string& f : fragments) {
      EXPECT_NE(r.err.find(f), std::string::npos) << "'" << f << "' not in stderr: " << r.err;
    }
    EXPECT_FALSE(fs::exists(out + "/summary.json"));
    // Nor any other file: the estimate files being written when the bad row came are
    // temporaries, removed (the input is read as the run goes).
    if (fs::exists(out)) {
      EXPECT_TRUE(fs::is_empty(out)) << out;
    }
  }

  /// Edits one line (1-based) of a dataset file.
  void EditLine(const std::string& file,
                int line,
                const std::function<std::string(const std::string&)>& edit) {
    std::vector<std::string> lines = ReadLines(data_ + "/" + file);
    ASSERT_GE(static_cast<int>(lines.size()), line);
    lines[line - 1] = edit(lines[line - 1]);
    WriteLines(data_ + "/" + file, lines);
  }

  std::string data_;
};

TEST_F(CliBadInputTest, TruncatedImuLine) {
  EditLine("imu.csv", 100, [](const std::string& l) {
    std::vector<std::string> f = Split(l);
    f.resize(4);  // t, wx, wy, wz: the accelerometer columns are missing
    return Join(f);
  });
  ExpectRunFails({"imu.csv:100: ax"});
}

TEST_F(CliBadInputTest, NanInGnss) {
  EditLine("gnss.csv", 10, [](const std::string& l) {
    std::vector<std::string> f = Split(l);
    f[1] = "nan";
    return Join(f);
  });
  ExpectRunFails({"gnss.csv:10: lat"});
}

// A header-only file is an empty file, said as such (it used to surface as "the estimator never
// initialised").
// Found as the run reaches it, near the end of the recording.
TEST_F(CliBadInputTest, ABadRowAtTheEndOfTheImuFile) {
  const int last = static_cast<int>(ReadLines(data_ + "/imu.csv").size());
  EditLine("imu.csv", last - 1, [](const std::string& l) {
    std::vector<std::string> f = Split(l);
    f[5] = "inf";
    return Join(f);
  });
  ExpectRunFails({"imu.csv:" + std::to_string(last - 1) + ": ay"});
}

// A fix after the last IMU sample is not used, but it is read and checked as the others are:
// here the second of two such fixes (the first is read ahead while the IMU still runs).
TEST_F(CliBadInputTest, ABadFixAfterTheLastImuSample) {
  std::vector<std::string> lines = ReadLines(data_ + "/gnss.csv");
  std::vector<std::string> f = Split(lines.back());
  f[0] = std::to_string(std::stod(f[0]) + 1000.0);  // long after the IMU record
  lines.push_back(Join(f));
  f[0] = std::to_string(std::stod(f[0]) + 1.0);
  f[2] = "200";
  lines.push_back(Join(f));
  WriteLines(data_ + "/gnss.csv", lines);
  ExpectRunFails({"gnss.csv:" + std::to_string(lines.size()) + ": lon"});
}

TEST_F(CliBadInputTest, HeaderOnlyImuFileIsEmpty) {
  WriteLines(data_ + "/imu.csv", {ReadLines(data_ + "/imu.csv").front()});
  ExpectRunFails({"imu.csv: t: no IMU samples"});
}

TEST_F(CliBadInputTest, HeaderOnlyGnssFileHasNoFixes) {
  WriteLines(data_ + "/gnss.csv", {ReadLines(data_ + "/gnss.csv").front()});
  ExpectRunFails({"gnss.csv: t: no fixes"});
}

// sensors.imu.gravity_m_s2 of datasets written before the Earth model: refused, with where it
// went (a silent default would change what the dataset means).
TEST_F(CliBadInputTest, GravityUnderTheImuIsRefused) {
  std::vector<std::string> lines = ReadLines(data_ + "/dataset.yaml");
  for (size_t k = 0; k < lines.size(); ++k) {
    if (lines[k].find("file: imu.csv") != std::string::npos) {
      lines.insert(lines.begin() + static_cast<long>(k) + 1, "    gravity_m_s2: 9.81");
      break;
    }
  }
  WriteLines(data_ + "/dataset.yaml", lines);
  ExpectRunFails({"dataset.yaml:", "sensors.imu.gravity_m_s2: moved", "earth:"});
}

TEST_F(CliBadInputTest, NonIncreasingImuTime) {
  std::string previous_time;
  EditLine("imu.csv", 49, [&](const std::string& l) {
    previous_time = Split(l)[0];
    return l;
  });
  EditLine("imu.csv", 50, [&](const std::string& l) {
    std::vector<std::string> f = Split(l);
    f[0] = previous_time;
    return Join(f);
  });
  ExpectRunFails({"imu.csv:50: t"});
}

TEST_F(CliBadInputTest, DatasetYamlMissingRequiredKey) {
  // Drop sensors.imu.rate_hz; the error is reported where the sensors.imu mapping starts.
  std::vector<std::string> lines = ReadLines(data_ + "/dataset.yaml");
  int imu_line = 0, removed = 0;
  std::vector<std::string> kept;
  for (size_t k = 0; k < lines.size(); ++k) {
    if (lines[k].find("imu:") != std::string::npos && imu_line == 0) {
      imu_line = static_cast<int>(k) + 1;
    }
    if (imu_line > 0 && removed == 0 && lines[k].find("rate_hz:") != std::string::npos) {
      removed = static_cast<int>(k) + 1;
      continue;
    }
    kept.push_back(lines[k]);
  }
  ASSERT_GT(imu_line, 0);
  ASSERT_GT(removed, imu_line);
  WriteLines(data_ + "/dataset.yaml", kept);
  // The mapping's first key is on the line after "imu:" (unless rate_hz itself was it).
  const int mapping_line = imu_line + 1;
  ExpectRunFails({"dataset.yaml:" + std::to_string(mapping_line) + ": sensors.imu.rate_hz"});
}

TEST_F(CliBadInputTest, UnknownSensorKind) {
  std::vector<std::string> lines = ReadLines(data_ + "/dataset.yaml");
  std::vector<std::string> edited;
  int sensor_line = 0;
  for (const std::string& l : lines) {
    edited.push_back(l);
    if (l.rfind("sensors:", 0) == 0) {
      edited.push_back("  sonar:");
      edited.push_back("    file: sonar.csv");
      sensor_line = static_cast<int>(edited.size()) - 1;
    }
  }
  ASSERT_GT(sensor_line, 0);
  WriteLines(data_ + "/dataset.yaml", edited);
  ExpectRunFails({"dataset.yaml:" + std::to_string(sensor_line) + ": sensors.sonar"});
}

TEST_F(CliBadInputTest, UnknownPreset) {
  ExpectRunFails({"no-such-preset", "(preset)"}, "--config no-such-preset");
}

TEST_F(CliBadInputTest, BadSetNamesTheOverride) {
  ExpectRunFails({"(command line): --set skyline.dem_spacing_m: must be >= 0"},
                 "--set skyline.dem_spacing_m=-1");
  ExpectRunFails({"(command line): --set solver.max_iteration: unknown key"},
                 "--set solver.max_iteration=3");
  ExpectRunFails({"--set", "expected KEY=VALUE"}, "--set window_keyframes");
}

TEST_F(CliBadInputTest, UnknownKeyInConfig) {
  const std::string config = FreshDir("config") + "/tuning.yaml";
  WriteText(config, "name: tuning\nwindow_keyframs: 5\n");
  ExpectRunFails({"tuning.yaml:2: window_keyframs"}, "--config " + Quote(config));
}

// `import`'s fix flags: a bad rate or sigma names the flag; fixes made from ground truth need a
// sequence that has one (an ASL sequence may come without), and are for EuRoC only; their noise
// follows --seed, which is checked as simulate's is.
TEST(CliTest, ImportFixFlagsNameWhatIsWrong) {
  const std::string euroc = std::string(SKERRY_SHARED_DATA_DIR) + "/euroc_v1_01";
  if (!fs::exists(euroc)) GTEST_SKIP() << euroc << " missing";
  const std::string out = FreshDir("import_out");
  auto fails = [&](const std::string& args, const std::string& what) {
    const CliResult r = RunCli("import --out " + Quote(out) + " " + args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(what), std::string::npos) << args << "\n" << r.err;
  };
  const std::string in = "--format euroc --input " + Quote(euroc);
  fails(in + " --fixes-rate 2 --fixes-sigma 0", "--fixes-sigma");
  fails(in + " --fixes-rate -1", "--fixes-rate");
  fails("--format husky --input " + Quote(euroc) + " --fixes-rate 2", "--fixes-rate");
  // --seed: the fixes' noise. A seed that is not one is refused (as simulate's: SeedNumber); the
  // same seed makes the same dataset, another seed other fixes of the same sequence.
  for (const char* bad : {"-5", "18446744073709551616", "1.5"}) {
    fails(in + " --fixes-rate 2 --seed " + bad, "--seed: must be a whole number");
  }
  const auto imported = [&](const std::string& seed, const std::string& name) {
    const std::string dir = FreshDir(name) + "/data";
    const CliResult r =
        RunCli("import " + in + " --fixes-rate 2 --seed " + seed + " --out " + Quote(dir));
    EXPECT_EQ(r.status, 0) << r.err;
    return dir;
  };
  const std::string seven = imported("7", "seed7"), again = imported("7", "seed7_again"),
                    eight = imported("8", "seed8");
  for (const auto& entry : fs::directory_iterator(seven)) {
    const std::string file = entry.path().filename().string();
    EXPECT_EQ(ReadText(again + "/" + file), ReadText(seven + "/" + file)) << file;
  }
  // The fixes are the dataset's GNSS: other noise, the same times.
  const std::vector<std::string> fixes7 = ReadLines(seven + "/gnss.csv"),
                                 fixes8 = ReadLines(eight + "/gnss.csv");
  ASSERT_EQ(fixes7.size(), fixes8.size());
  ASSERT_GT(fixes7.size(), 100u);
  EXPECT_NE(fixes7, fixes8);
  EXPECT_EQ(fixes7[5].substr(0, fixes7[5].find(',')), fixes8[5].substr(0, fixes8[5].find(',')));
  EXPECT_EQ(ReadText(eight + "/imu.csv"), ReadText(seven + "/imu.csv"));
  // An ASL sequence with its IMU and no ground truth.
  const fs::path mav0 = fs::path(FreshDir("asl_no_truth")) / "MH_01_easy" / "mav0";
  fs::create_directories(mav0 / "imu0");
  fs::copy_file(euroc + "/imu0_data.csv", mav0 / "imu0" / "data.csv");
  fs::copy_file(euroc + "/imu0_sensor.yaml", mav0 / "imu0" / "sensor.yaml");
  fails("--format euroc --input " + Quote(mav0.parent_path().string()) + " --fixes-rate 2",
        "no ground truth");
  // Without fix flags the same sequence imports (its IMU only).
  EXPECT_EQ(RunCli("import --format euroc --input " + Quote(mav0.parent_path().string()) +
                   " --out " + Quote(out))
                .status,
            0);
}

TEST_F(CliBadInputTest, SmoothReportsTheSameWay) {
  EditLine("gnss.csv", 5, [](const std::string& l) {
    std::vector<std::string> f = Split(l);
    f[4] = "-0.5";  // sigma_e must be positive
    return Join(f);
  });
  const std::string out = FreshDir("out");
  const CliResult r = RunCli("smooth --dataset " + Quote(data_) + " --out " + Quote(out));
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("gnss.csv:5: sigma_e"), std::string::npos) << r.err;
}

TEST_F(CliBadInputTest, GoodDatasetRuns) {
  // Control for the tests above: the unedited dataset runs (status 0).
  const std::string out = FreshDir("out");
  const CliResult r = RunCli("run --dataset " + Quote(data_) + " --out " + Quote(out) + " -q");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(out + "/summary.json"));
}

}  // namespace
}  // namespace skerry
