// `skerry compare` end to end through the real binary: the local path (parallel runs, table,
// Hellinger fidelity), the plan -> jobs.txt / GNU parallel / Slurm runner -> collect round trip,
// and bad input. docs/compare.md describes the folder these tests read.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "apps/cli_test_util.h"
#include "core/test_util.h"
#include "skerry/eval/evaluation.h"
#include "skerry/io/estimate_io.h"
#include "skerry/io/trajectory.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::Child;
using testing::CliResult;
using testing::FreshDir;
using testing::Quote;
using testing::ReadLines;
using testing::ReadText;
using testing::RunCli;
using testing::ShortScenarioYaml;
using testing::WriteText;

/// Three configurations: `good` (the default), `good-copy` (the same under another name) and
/// `bad` (short window, no gate or robust loss, receiver sigmas trusted 3x too much). No solver
/// time budget, so the runs are deterministic and two runs of the same job agree to the bit.
struct Fixture {
  std::string dir;
  std::string scenario;
  std::vector<std::string> configs;
};

Fixture MakeFixture(const std::string& name) {
  Fixture f;
  f.dir = FreshDir(name);
  f.scenario = f.dir + "/scenario.yaml";
  WriteText(
      f.scenario,
      ShortScenarioYaml(150.0, "harbour-short",
                        "  jumps:\n"
                        "    - {start_s: 80, duration_s: 20, offset_enu_m: [14.5, 0.0, 0.0]}\n"));
  const std::vector<std::pair<std::string, std::string>> yaml = {
      {"good", "name: good\nsolver: {max_time_s: 0}\n"},
      {"good-copy", "name: good-copy\nsolver: {max_time_s: 0}\n"},
      {"bad",
       "name: bad\nwindow_keyframes: 3\nfirst_estimate_jacobians: false\n"
       "gnss: {loss: none, gate_probability: 0, sigma_scale: 0.3}\nsolver: {max_time_s: 0}\n"}};
  for (const auto& [config, text] : yaml) {
    const std::string path = f.dir + "/" + config + ".yaml";
    WriteText(path, text);
    f.configs.push_back(path);
  }
  return f;
}

std::string CompareArgs(const Fixture& f, const std::string& out) {
  std::string args = "compare --dataset " + Quote(f.scenario) + " --seeds 2 --out " + Quote(out);
  for (const std::string& c : f.configs) args += " --config " + Quote(c);
  return args;
}

nlohmann::json ReadJson(const std::string& path) { return nlohmann::json::parse(ReadText(path)); }

const nlohmann::json& Row(const nlohmann::json& table, const std::string& config) {
  for (const nlohmann::json& row : table["rows"]) {
    if (row["config"] == config) return row;
  }
  ADD_FAILURE() << "no row for " << config;
  static const nlohmann::json empty;
  return empty;
}

/// The table without the wall-clock figures (which differ between two runs of the same job).
nlohmann::json WithoutTimes(nlohmann::json table) {
  for (nlohmann::json& row : table["rows"]) {
    row.erase("update_ms");
    for (nlohmann::json& r : row["per_run"]) {
      for (const char* key : {"wall_s", "update_ms_median", "update_ms_p95", "update_ms_max"}) {
        r.erase(key);
      }
    }
  }
  return table;
}

class CompareCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fixture_ = new Fixture(MakeFixture("compare_fixture"));
    local_ = fixture_->dir + "/local";
    const CliResult r = RunCli(CompareArgs(*fixture_, local_) + " --jobs 2");
    local_status_ = r.status;
    local_out_ = r.out + r.err;
  }
  // A failure in SetUpTestSuite would only skip the tests: fail each of them instead.
  void SetUp() override { ASSERT_EQ(local_status_, 0) << local_out_; }
  static void TearDownTestSuite() { delete fixture_; }
  static Fixture* fixture_;
  static std::string local_;
  static std::string local_out_;
  static int local_status_;
};
Fixture* CompareCli::fixture_ = nullptr;
std::string CompareCli::local_;
std::string CompareCli::local_out_;
int CompareCli::local_status_ = -1;

TEST_F(CompareCli, LocalRunWritesTheTable) {
  const nlohmann::json table = ReadJson(local_ + "/table.json");
  EXPECT_EQ(table["reference_config"], "good");
  ASSERT_EQ(table["rows"].size(), 3u);
  for (const nlohmann::json& row : table["rows"]) {
    SCOPED_TRACE(row["config"].get<std::string>());
    EXPECT_EQ(row["runs"], 2);
    EXPECT_EQ(row["failed_runs"], 0);
    EXPECT_EQ(row["per_run"].size(), 2u);
    EXPECT_GT(row["share_valid"].get<double>(), 0.9);
    EXPECT_LE(row["share_valid"].get<double>(), 1.0);
    EXPECT_GT(row["update_ms"]["median"].get<double>(), 0.0);
    EXPECT_GE(row["update_ms"]["max"].get<double>(), row["update_ms"]["p95"].get<double>());
    EXPECT_GT(row["iterations"]["mean"].get<double>(), 0.0);
    const double lo = row["anees_bounds_95"][0], hi = row["anees_bounds_95"][1];
    EXPECT_LT(lo, 3.0);
    EXPECT_GT(hi, 3.0);
    EXPECT_TRUE(row["consistency"] == "consistent" || row["consistency"] == "overconfident" ||
                row["consistency"] == "underconfident");
    const double inside = row["nees_inside_95"], above = row["nees_above_95"],
                 below = row["nees_below_95"];
    EXPECT_NEAR(inside + above + below, 1.0, 1e-12);
    EXPECT_GT(row["nees_epochs"].get<int>(), 1000);
  }
  const nlohmann::json& good = Row(table, "good");
  const nlohmann::json& bad = Row(table, "bad");
  EXPECT_TRUE(good["ahed"].is_null());
  // The harbour receiver's multipath and latency (docs/simulator.md) are in these 150 s.
  EXPECT_LT(good["horizontal_rmse_m"].get<double>(), 1.0);
  // The jump drags the ungated configuration; its sigmas are 3x too small.
  EXPECT_GT(bad["jump_max_error_m"].get<double>(), 3.0);
  EXPECT_LT(good["jump_max_error_m"].get<double>(), 1.5);
  EXPECT_EQ(bad["consistency"], "overconfident");
  EXPECT_LT(bad["nees_inside_95"].get<double>(), 0.9);
  EXPECT_GT(bad["nees_above_95"].get<double>(), bad["nees_below_95"].get<double>());
  EXPECT_GT(good["nees_inside_95"].get<double>(), bad["nees_inside_95"].get<double>());

  // The terminal shows the table; table.csv and runs.csv hold it too.
  EXPECT_NE(local_out_.find("good-copy"), std::string::npos);
  EXPECT_EQ(ReadLines(local_ + "/table.csv").size(), 4u);
  EXPECT_EQ(ReadLines(local_ + "/runs.csv").size(), 7u);
  EXPECT_EQ(ReadLines(local_ + "/table.csv")[0].rfind("dataset,config,reference,runs", 0), 0u);
}

/// The table's pooled figures, recomputed here from the run folders and the datasets with the
/// core evaluation: RMSE over all epochs of both seeds, maxima, ANEES, and the per-epoch
/// Monte-Carlo NEES test (seed-averaged NEES inside the chi2(3N)/N 95 % bounds, epochs matched
/// on the keyframe grid).
TEST_F(CompareCli, PooledFiguresMatchARecomputationFromTheRuns) {
  const nlohmann::json table = ReadJson(local_ + "/table.json");
  for (const char* config : {"good", "bad"}) {
    SCOPED_TRACE(config);
    double sum_sq = 0.0, max_h = 0.0, nees_sum = 0.0;
    int n = 0, nees_n = 0;
    std::map<TimeNs, std::pair<double, int>> by_epoch;
    for (int seed : {1, 2}) {
      const std::string run =
          local_ + "/runs/harbour-short/" + config + "/seed-" + std::to_string(seed);
      const std::string data = local_ + "/datasets/harbour-short/seed-" + std::to_string(seed);
      const EvaluationResult ev =
          Evaluate(ReadEstimate(run + "/states.csv", run + "/covariances.csv"),
                   ReadTum(data + "/groundtruth.tum"));
      for (const EpochError& e : ev.epochs) {
        const double h = e.p_err_w.head<2>().norm();
        sum_sq += h * h;
        max_h = std::max(max_h, h);
        ++n;
        if (!e.has_nees) continue;
        nees_sum += e.nees_pos;
        ++nees_n;
        // Epochs of the two seeds matched on the 10 Hz keyframe grid (their first fixes, and so
        // their keyframes, are stamped a few milliseconds apart).
        const TimeNs period = 100'000'000;
        const TimeNs key = (e.t_ns + period / 2) / period * period;
        by_epoch[key].first += e.nees_pos;
        ++by_epoch[key].second;
      }
    }
    int inside = 0;
    for (const auto& [t, sc] : by_epoch) {
      const auto b = AneesBounds(3, sc.second);
      const double mean = sc.first / sc.second;
      inside += (mean >= b.first && mean <= b.second) ? 1 : 0;
    }
    const nlohmann::json& row = Row(table, config);
    EXPECT_NEAR(row["horizontal_rmse_m"].get<double>(), std::sqrt(sum_sq / n), 1e-9);
    EXPECT_NEAR(row["horizontal_max_m"].get<double>(), max_h, 1e-12);
    EXPECT_EQ(row["nees_count"].get<int>(), nees_n);
    EXPECT_NEAR(row["anees_position"].get<double>(), nees_sum / nees_n, 1e-9);
    EXPECT_EQ(row["nees_epochs"].get<int>(), static_cast<int>(by_epoch.size()));
    EXPECT_NEAR(row["nees_inside_95"].get<double>(), static_cast<double>(inside) / by_epoch.size(),
                1e-12);
  }
}

TEST_F(CompareCli, SameConfigurationHasZeroHellingerAndABadOneDoesNot) {
  const nlohmann::json table = ReadJson(local_ + "/table.json");
  const nlohmann::json& copy = Row(table, "good-copy");
  const nlohmann::json& bad = Row(table, "bad");
  for (const char* block : {"position", "heading", "attitude", "velocity", "biases", "full"}) {
    SCOPED_TRACE(block);
    EXPECT_EQ(copy["ahed"][block].get<double>(), 0.0);
    EXPECT_GT(bad["ahed"][block].get<double>(), 0.1);
  }
  EXPECT_EQ(copy["share_one_valid"].get<double>(), 0.0);
  // Identical runs: identical figures.
  EXPECT_EQ(copy["horizontal_rmse_m"], Row(table, "good")["horizontal_rmse_m"]);
  // The per-epoch file of the report.
  const std::string csv = local_ + "/fidelity/harbour-short/bad/seed-1.csv";
  ASSERT_TRUE(fs::exists(csv));
  const std::vector<std::string> lines = ReadLines(csv);
  EXPECT_GT(lines.size(), 1000u);
  EXPECT_EQ(lines[0].rfind("t,valid_a,valid_b,hed_position", 0), 0u);
}

TEST_F(CompareCli, FidelityOfTwoRunFolders) {
  const std::string runs = local_ + "/runs/harbour-short/";
  const std::string csv = fixture_->dir + "/fidelity.csv";
  CliResult r = RunCli("fidelity --a " + Quote(runs + "good/seed-1") + " --b " +
                       Quote(runs + "good-copy/seed-1") + " --csv " + Quote(csv));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("position    0.0000"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("only one at 0 (0.0%)"), std::string::npos) << r.out;
  // Each block's floor (hellinger_floor.h): position 3-D, heading 1-D.
  EXPECT_NE(r.out.find("0.6461"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0.3575"), std::string::npos) << r.out;
  EXPECT_GT(ReadLines(csv).size(), 1000u);
  r = RunCli("fidelity --a " + Quote(runs + "good/seed-1") + " --b " + Quote(runs + "bad/seed-1"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out.find("position    0.0000"), std::string::npos) << r.out;
  // The same run on another clock (times + 1000 s): nothing matches as it is, everything with
  // --align-start or the right --offset.
  const std::string shifted = fixture_->dir + "/shifted";
  fs::create_directories(shifted);
  for (const char* file : {"states.csv", "covariances.csv"}) {
    std::vector<std::string> lines = ReadLines(runs + "good/seed-1/" + file);
    for (size_t i = 1; i < lines.size(); ++i) {
      const size_t comma = lines[i].find(',');
      char t[32];
      std::snprintf(t, sizeof(t), "%.9f", std::stod(lines[i].substr(0, comma)) + 1000.0);
      lines[i] = t + lines[i].substr(comma);
    }
    testing::WriteLines(shifted + "/" + file, lines);
  }
  r = RunCli("fidelity --a " + Quote(runs + "good/seed-1") + " --b " + Quote(shifted));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("both valid at 0,"), std::string::npos) << r.out;
  for (const std::string& how : {std::string("--align-start"), std::string("--offset -1000")}) {
    r = RunCli("fidelity --a " + Quote(runs + "good/seed-1") + " --b " + Quote(shifted) + " " +
               how);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("B's times moved by -1000.000000 s"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("position    0.0000"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("only one at 0 (0.0%)"), std::string::npos) << r.out;
  }
  // An offset that is no time: the option named as --until's is (command_line_time.h), exit 2.
  for (const char* bad : {"nan", "1e300", "-inf"}) {
    r = RunCli("fidelity --a " + Quote(runs + "good/seed-1") + " --b " + Quote(shifted) +
               " --offset " + bad);
    EXPECT_EQ(r.status, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find("--offset: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("must be a finite time in seconds, within +-1e+09 s"), std::string::npos)
        << r.err;
  }
  // The epoch tolerance out of its range: the option named, exit 2 (CompareRuns' own
  // std::invalid_argument exited 1).
  for (const char* bad : {"nan", "-1", "1e300"}) {
    r = RunCli("fidelity --a " + Quote(runs + "good/seed-1") + " --b " + Quote(shifted) +
               " --tolerance " + bad);
    EXPECT_EQ(r.status, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find("--tolerance: must be in [0, 3600] s"), std::string::npos) << r.err;
  }
  // Not a run folder.
  r = RunCli("fidelity --a " + Quote(local_) + " --b " + Quote(runs + "bad/seed-1"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("states.csv"), std::string::npos) << r.err;
}

TEST_F(CompareCli, PlanJobsAndCollectReproduceTheLocalTable) {
  const std::string planned = fixture_->dir + "/planned";
  CliResult r = RunCli(CompareArgs(*fixture_, planned) + " --plan");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("planned 6 jobs (1 scenario(s) x 2 seed(s) x 3 configuration(s))"),
            std::string::npos)
      << r.out;
  const std::vector<std::string> jobs = ReadLines(planned + "/jobs.txt");
  ASSERT_EQ(jobs.size(), 6u);
  // Seeds multiply scenarios only: a recorded dataset folder runs once per configuration, and
  // the plan says so rather than "x 4 seeds" beside 3 jobs.
  std::string folder;
  for (const auto& e : fs::recursive_directory_iterator(local_)) {
    if (e.path().filename() == "dataset.yaml") {
      folder = e.path().parent_path().string();
      break;
    }
  }
  ASSERT_FALSE(folder.empty()) << "no dataset folder in " << local_;
  std::string configs;
  for (const std::string& c : fixture_->configs) configs += " --config " + Quote(c);
  r = RunCli("compare --dataset " + Quote(folder) + " --seeds 4" + configs + " --out " +
             Quote(fixture_->dir + "/folder_plan") + " --plan");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("planned 3 jobs (1 dataset folder(s) x 3 configuration(s); --seeds 4 "
                       "applies to simulated scenarios, a folder runs once)"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(ReadLines(fixture_->dir + "/folder_plan/jobs.txt").size(), 3u);
  EXPECT_FALSE(fs::exists(planned + "/table.json"));
  // Collecting before any job ran: every run is missing, exit status 3.
  r = RunCli("compare --collect " + Quote(planned));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("6 job(s) have no result"), std::string::npos) << r.err;

  // Job 0 through the Slurm script (as one array task would run it), the others as the lines
  // of jobs.txt (as GNU parallel or a shell would).
  const std::string slurm =
      "cd " + Quote(planned) + " && SLURM_ARRAY_TASK_ID=0 bash slurm_array.sh";
  ASSERT_EQ(std::system(slurm.c_str()), 0);
  EXPECT_TRUE(fs::exists(planned + "/runs/harbour-short/good/seed-1/result.json"));
  for (size_t i = 1; i < jobs.size(); ++i) {
    ASSERT_EQ(std::system(jobs[i].c_str()), 0) << jobs[i];
  }
  r = RunCli("compare --collect " + Quote(planned));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(WithoutTimes(ReadJson(planned + "/table.json")),
            WithoutTimes(ReadJson(local_ + "/table.json")));
}

TEST_F(CompareCli, GnuParallelRunnerRunsThePlan) {
  if (std::system("command -v parallel > /dev/null") != 0) {
    GTEST_SKIP() << "GNU parallel is not installed (scripts/setup.sh installs it)";
  }
  const std::string planned = fixture_->dir + "/parallel";
  CliResult r = RunCli(CompareArgs(*fixture_, planned) + " --plan");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string cmd = "JOBS=2 bash " + Quote(planned + "/run_parallel.sh") + " > " +
                          Quote(planned + "/runner.log") + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadText(planned + "/runner.log");
  EXPECT_EQ(WithoutTimes(ReadJson(planned + "/table.json")),
            WithoutTimes(ReadJson(local_ + "/table.json")));
}

std::vector<std::string> CompareArgv(const Fixture& f, const std::string& out) {
  std::vector<std::string> args = {"compare",  "-q",      "--jobs", "1",     "--dataset",
                                   f.scenario, "--seeds", "2",      "--out", out};
  for (const std::string& c : f.configs) {
    args.push_back("--config");
    args.push_back(c);
  }
  return args;
}

std::vector<std::string> Results(const std::string& out) {
  std::vector<std::string> found;
  for (const auto& e : fs::recursive_directory_iterator(out + "/runs")) {
    if (e.path().filename() == "result.json") found.push_back(e.path().string());
  }
  return found;
}

// A sweep killed (SIGKILL) after some of its runs resumes with only the missing ones: the runs
// done before are not run again, and the table is the one an uninterrupted sweep made.
TEST_F(CompareCli, AKilledSweepResumesWithOnlyTheMissingRuns) {
  const std::string out = fixture_->dir + "/killed";
  {
    const Child child(CompareArgv(*fixture_, out));
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (std::chrono::steady_clock::now() < deadline &&
           (!fs::exists(out + "/runs") || Results(out).size() < 2)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    child.Signal(SIGKILL);
    child.Wait();
  }
  const std::vector<std::string> done = Results(out);
  ASSERT_GE(done.size(), 2u);
  ASSERT_LT(done.size(), 6u) << "the sweep finished before it was killed";
  std::vector<fs::file_time_type> written;
  for (const std::string& path : done) written.push_back(fs::last_write_time(path));

  const CliResult r = RunCli(CompareArgs(*fixture_, out) + " --jobs 2");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("resuming the sweep"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(std::to_string(done.size()) + " of 6 runs have their results"),
            std::string::npos)
      << r.out;
  for (size_t k = 0; k < done.size(); ++k) {
    EXPECT_EQ(fs::last_write_time(done[k]), written[k]) << done[k] << " was run again";
  }
  EXPECT_EQ(Results(out).size(), 6u);
  EXPECT_EQ(WithoutTimes(ReadJson(out + "/table.json")),
            WithoutTimes(ReadJson(local_ + "/table.json")));

  // Another plan in the same folder is refused; --overwrite replaces the comparison whole.
  const std::string other = "compare -q --dataset " + Quote(fixture_->scenario) +
                            " --seeds 1 --config " + Quote(fixture_->configs[0]) + " --out " +
                            Quote(out);
  CliResult o = RunCli(other);
  EXPECT_EQ(o.status, 2) << o.err;
  EXPECT_NE(o.err.find("--overwrite"), std::string::npos) << o.err;
  EXPECT_EQ(Results(out).size(), 6u) << "a refused plan removed results";
  o = RunCli(other + " --overwrite");
  ASSERT_EQ(o.status, 0) << o.err;
  EXPECT_EQ(Results(out).size(), 1u);
  EXPECT_EQ(ReadJson(out + "/table.json")["rows"].size(), 1u);
}

TEST(CompareCliFailures, AFailingConfigurationIsAResultNotACrash) {
  const Fixture f = MakeFixture("compare_failure");
  // Initialisation from a dual-antenna heading, on data without one: it never initialises.
  WriteText(f.dir + "/never.yaml", "name: never\ninit: {mode: heading}\n");
  const std::string out = f.dir + "/out";
  const CliResult r =
      RunCli("compare -q --dataset " + Quote(f.scenario) + " --config " + Quote(f.configs[0]) +
             " --config " + Quote(f.dir + "/never.yaml") + " --out " + Quote(out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("1 run(s) failed"), std::string::npos) << r.err;
  const nlohmann::json table = ReadJson(out + "/table.json");
  const nlohmann::json& never = Row(table, "never");
  EXPECT_EQ(never["runs"], 1);
  EXPECT_EQ(never["failed_runs"], 1);
  EXPECT_EQ(never["share_valid"].get<double>(), 0.0);
  EXPECT_TRUE(never["horizontal_rmse_m"].is_null());
  EXPECT_EQ(never["share_one_valid"].get<double>(), 1.0);  // only the reference has estimates
  EXPECT_NE(never["per_run"][0]["error"].get<std::string>().find("never initialised"),
            std::string::npos);
  EXPECT_EQ(Row(table, "good")["failed_runs"], 0);
  // A run that died before writing anything but its result still counts its epochs.
  const std::string run = out + "/runs/harbour-short/never/seed-1";
  std::filesystem::remove(run + "/summary.json");
  ASSERT_EQ(RunCli("compare -q --collect " + Quote(out)).status, 0);
  const nlohmann::json again = ReadJson(out + "/table.json");
  EXPECT_EQ(Row(again, "never")["per_run"][0]["expected_epochs"],
            Row(again, "good")["per_run"][0]["expected_epochs"]);
  EXPECT_EQ(Row(again, "never")["share_valid"].get<double>(), 0.0);
}

// Variants of one preset on the command line (`--config SOURCE,KEY=VALUE`): each its own
// configuration file in the plan, under its own name, with its keys changed and no others.
TEST(CompareCliVariants, APresetWithKeysChangedIsAConfigurationOfItsOwn) {
  const Fixture f = MakeFixture("compare_variants");
  const std::string out = f.dir + "/plan";
  const CliResult r =
      RunCli("compare --dataset " + Quote(f.scenario) +
             " --config default --config default,skyline.dem_sharpening_sigma=1,solver.max_"
             "iterations=4 --plan --out " +
             Quote(out));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json plan = ReadJson(out + "/plan.json");
  ASSERT_EQ(plan["configs"].size(), 2u);
  EXPECT_EQ(plan["configs"][0]["name"], "default");
  const std::string variant = "default-dem_sharpening_sigma-1-max_iterations-4";
  EXPECT_EQ(plan["configs"][1]["name"], variant);
  const std::string plain = ReadText(out + "/configs/default.yaml");
  const std::string changed = ReadText(out + "/configs/" + variant + ".yaml");
  EXPECT_NE(plain.find("dem_sharpening_sigma: 0\n"), std::string::npos) << plain;
  EXPECT_NE(changed.find("dem_sharpening_sigma: 1\n"), std::string::npos) << changed;
  EXPECT_NE(changed.find("max_iterations: 4\n"), std::string::npos) << changed;
  // A bad value names the option and the key.
  const CliResult bad =
      RunCli("compare --dataset " + Quote(f.scenario) +
             " --config default,solver.max_iterations=many --plan --out " + Quote(f.dir + "/bad"));
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("--config solver.max_iterations"), std::string::npos) << bad.err;
}

// The dataset's sensors beyond IMU and GNSS take part as in `skerry run` (they were left out:
// a skyline or harbour dataset was compared on its IMU and GNSS alone).
TEST(CompareCliSensors, TheDatasetsFrontendsTakePart) {
  const std::string dir = FreshDir("compare_sensors");
  const std::string scenario = dir + "/scenario.yaml";
  WriteText(scenario, ShortScenarioYaml(40.0, "harbour-water") +
                          "water_surface: {enabled: true, sigma_m: 0.3, rate_hz: 1}\n");
  const std::string out = dir + "/out";
  const CliResult r = RunCli("compare --dataset " + Quote(scenario) +
                             " --config default --jobs 1 --quiet --out " + Quote(out));
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string run = out + "/runs/harbour-water/default/seed-1";
  const nlohmann::json summary = ReadJson(run + "/summary.json");
  const nlohmann::json& sensors = summary["solver"]["sensors"];
  ASSERT_TRUE(sensors.contains("water_surface")) << summary["solver"].dump();
  EXPECT_GE(sensors["water_surface"]["accepted"].get<int>(), 30);
  const std::vector<std::string> blocks = ReadLines(run + "/blocks.csv");
  ASSERT_GE(blocks.size(), 31u);
  EXPECT_EQ(blocks[0].rfind("t,sensor,decision", 0), 0u) << blocks[0];
  EXPECT_NE(blocks[1].find(",water_surface,"), std::string::npos) << blocks[1];
}

TEST(CompareCliErrors, BadInputNamesTheProblem) {
  const Fixture f = MakeFixture("compare_errors");
  // An unknown preset.
  CliResult r = RunCli("compare --dataset " + Quote(f.scenario) +
                       " --config no-such-preset --out " + Quote(f.dir + "/a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("no-such-preset"), std::string::npos) << r.err;
  // Two configurations of the same name.
  r = RunCli("compare --dataset " + Quote(f.scenario) + " --config " + Quote(f.configs[0]) +
             " --config " + Quote(f.configs[0]) + " --out " + Quote(f.dir + "/b"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--config"), std::string::npos) << r.err;
  // A first seed that is not one (CLI11 alone took -1, and clamped one past the int64 range).
  for (const char* bad : {"-1", "9223372036854775807", "1e3"}) {
    r = RunCli("compare --dataset " + Quote(f.scenario) + " --first-seed " + bad + " --out " +
               Quote(f.dir + "/seed"));
    EXPECT_EQ(r.status, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find("--first-seed"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("must be a whole number from 0 to 4611686018427387903"), std::string::npos)
        << r.err;
  }
  // A folder that is not a dataset.
  r = RunCli("compare --dataset " + Quote(f.dir) + " --config default --out " +
             Quote(f.dir + "/c"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("dataset.yaml"), std::string::npos) << r.err;
  // Collecting a folder without a plan, and a plan with a field missing.
  r = RunCli("compare --collect " + Quote(f.dir + "/nothing"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("plan.json"), std::string::npos) << r.err;
  const std::string planned = f.dir + "/d";
  ASSERT_EQ(RunCli("compare --dataset " + Quote(f.scenario) + " --config default --plan --out " +
                   Quote(planned))
                .status,
            0);
  // A job number the plan does not have.
  r = RunCli("compare --out " + Quote(planned) + " --job 7");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--job"), std::string::npos) << r.err;
  const std::string plan = ReadText(planned + "/plan.json");
  const size_t at = plan.find("\"run_dir\"");
  ASSERT_NE(at, std::string::npos);
  WriteText(planned + "/plan.json", plan.substr(0, at) + "\"rundir\"" + plan.substr(at + 9));
  r = RunCli("compare --collect " + Quote(planned));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("plan.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("jobs[0].run_dir"), std::string::npos) << r.err;
  // A run folder whose name no file system can hold (the fuzzer's find: std::filesystem threw
  // ENAMETOOLONG out of --collect), and one with a NUL byte in it.
  const std::string long_name = "runs/" + std::string(300, 'x');
  const size_t value = plan.find("\"runs/", at);
  ASSERT_NE(value, std::string::npos);
  WriteText(planned + "/plan.json",
            plan.substr(0, value + 1) + long_name + "/" + plan.substr(value + 6));
  r = RunCli("compare --collect " + Quote(planned));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("jobs[0].run_dir"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("255 bytes"), std::string::npos) << r.err;
  WriteText(planned + "/plan.json",
            plan.substr(0, value + 1) + "runs/a\\u0000b/" + plan.substr(value + 6));
  r = RunCli("compare --collect " + Quote(planned));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("jobs[0].run_dir"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("NUL"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace skerry
