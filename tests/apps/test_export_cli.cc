// End to end through the real `skerry` binary: simulate -> run -> export to TUM, KITTI and EuRoC
// CSV -> evaluate each exported file, which must give the figures of trajectory.tum; and bad
// input to export / evaluate, which must exit with status 2 naming file:line and field.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "apps/cli_test_util.h"
#include "core/test_util.h"
#include "skerry/io/trajectory_formats.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::FreshDir;
using testing::Quote;
using testing::ReadLines;
using testing::RunCli;
using testing::ShortScenarioYaml;
using testing::WriteLines;
using testing::WriteText;

/// The horizontal RMSE of `skerry evaluate`, as printed (3 decimals) and, full precision, from
/// its --json output; empty / NaN when missing.
struct Rmse {
  std::string printed;
  double json = std::nan("");
};

Rmse HorizontalRmse(const CliResult& r, const std::string& json_path) {
  Rmse rmse;
  std::smatch m;
  if (std::regex_search(r.out, m, std::regex("horizontal RMSE ([0-9.]+) m"))) rmse.printed = m[1];
  const nlohmann::json j =
      nlohmann::json::parse(testing::ReadText(json_path), nullptr, /*allow_exceptions=*/false);
  if (!j.is_discarded() && j.contains("horizontal_m")) {
    rmse.json = j["horizontal_m"]["rmse"].get<double>();
  }
  return rmse;
}

/// Runs `skerry evaluate`; `rmse` (if given) gets its horizontal RMSE.
CliResult Evaluate(const std::string& estimate,
                   const std::string& groundtruth,
                   Rmse* rmse = nullptr,
                   const std::string& extra = "") {
  const std::string json = FreshDir("eval") + "/eval.json";
  const CliResult r = RunCli("evaluate --estimate " + Quote(estimate) + " --groundtruth " +
                             Quote(groundtruth) + " --json " + Quote(json) + extra);
  if (rmse != nullptr) *rmse = HorizontalRmse(r, json);
  return r;
}

/// The same figures: the same printed text and JSON values within 1e-9 m.
void ExpectSameRmse(const Rmse& got, const Rmse& want) {
  EXPECT_EQ(got.printed, want.printed);
  EXPECT_NEAR(got.json, want.json, 1e-9);
}

Rmse EvaluateRmse(const std::string& estimate, const std::string& groundtruth) {
  Rmse rmse;
  const CliResult r = Evaluate(estimate, groundtruth, &rmse);
  EXPECT_EQ(r.status, 0) << r.err;
  return rmse;
}

/// One harbour run (seed 1, cut to 120 s) shared by the tests of this file.
class ExportCliTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs each test in its own process, in parallel.
    dir_ = new std::string(testing::FreshDir("ExportCliTest.shared"));
    WriteText(*dir_ + "/scenario.yaml", ShortScenarioYaml(120.0));
    const CliResult s = RunCli("simulate --scenario " + Quote(*dir_ + "/scenario.yaml") +
                               " --seed 1 --out " + Quote(Data()));
    if (s.status != 0) {
      setup_error_ = "simulate: " + s.err;
      return;
    }
    const CliResult r = RunCli("run -q --dataset " + Quote(Data()) + " --out " + Quote(Run()));
    if (r.status != 0) setup_error_ = "run: " + r.err;
  }
  // A failure in SetUpTestSuite would only skip the tests: fail each of them instead.
  void SetUp() override { ASSERT_TRUE(setup_error_.empty()) << setup_error_; }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string Data() { return *dir_ + "/data"; }
  static std::string Run() { return *dir_ + "/run"; }
  static std::string GroundTruth() { return Data() + "/groundtruth.tum"; }

  static std::string* dir_;
  static std::string setup_error_;
};

std::string* ExportCliTest::dir_ = nullptr;
std::string ExportCliTest::setup_error_;

TEST_F(ExportCliTest, EachFormatEvaluatesLikeTrajectoryTum) {
  Rmse rmse;
  const CliResult reference = Evaluate(Run() + "/trajectory.tum", GroundTruth(), &rmse);
  ASSERT_EQ(reference.status, 0) << reference.err;
  ASSERT_FALSE(rmse.printed.empty()) << reference.out;
  ASSERT_TRUE(std::isfinite(rmse.json));
  EXPECT_GT(rmse.json, 0.0);

  const std::string out = FreshDir("export");
  for (const std::string& format : std::vector<std::string>{"tum", "kitti", "euroc"}) {
    SCOPED_TRACE(format);
    const std::string ext = format == "euroc" ? "csv" : format;
    const std::string file = out + "/estimate." + ext;
    const CliResult e = RunCli("export --estimate " + Quote(Run() + "/states.csv") + " --format " +
                               format + " --out " + Quote(file));
    ASSERT_EQ(e.status, 0) << e.err;
    EXPECT_NE(e.out.find(file), std::string::npos) << e.out;  // says what it wrote
    ASSERT_TRUE(fs::is_regular_file(file));
    ExpectSameRmse(EvaluateRmse(file, GroundTruth()), rmse);
  }
  EXPECT_TRUE(fs::is_regular_file(out + "/estimate.kitti.times"));
  // EuRoC from states.csv carries velocity and biases: 17 columns.
  const std::vector<std::string> euroc = ReadLines(out + "/estimate.csv");
  ASSERT_GE(euroc.size(), 2u);
  EXPECT_EQ(std::count(euroc[1].begin(), euroc[1].end(), ','), 16) << euroc[1];
  EXPECT_EQ(euroc.size(), ReadLines(Run() + "/states.csv").size());

  // A trajectory file re-exported (format by extension, or given), and ground truth in the
  // other formats: still the same figures.
  const CliResult k2e = RunCli("export --estimate " + Quote(out + "/estimate.kitti") +
                               " --format euroc --out " + Quote(out + "/from_kitti.csv"));
  ASSERT_EQ(k2e.status, 0) << k2e.err;
  ExpectSameRmse(EvaluateRmse(out + "/from_kitti.csv", GroundTruth()), rmse);
  fs::copy_file(out + "/estimate.tum", out + "/estimate.traj");
  const CliResult given =
      RunCli("export --estimate " + Quote(out + "/estimate.traj") +
             " --input-format tum --format tum --out " + Quote(out + "/given.tum"));
  ASSERT_EQ(given.status, 0) << given.err;
  ExpectSameRmse(EvaluateRmse(out + "/given.tum", GroundTruth()), rmse);
  for (const std::string& format : std::vector<std::string>{"kitti", "euroc"}) {
    SCOPED_TRACE("ground truth as " + format);
    const std::string gt = out + "/groundtruth." + (format == "euroc" ? "csv" : format);
    const CliResult g = RunCli("export --estimate " + Quote(GroundTruth()) + " --format " + format +
                               " --out " + Quote(gt));
    ASSERT_EQ(g.status, 0) << g.err;
    ExpectSameRmse(EvaluateRmse(Run() + "/trajectory.tum", gt), rmse);
  }
  // Explicit formats on evaluate.
  Rmse explicit_rmse;
  const CliResult explicit_formats =
      Evaluate(out + "/estimate.traj", out + "/groundtruth.csv", &explicit_rmse,
               " --estimate-format tum --groundtruth-format euroc");
  ASSERT_EQ(explicit_formats.status, 0) << explicit_formats.err;
  ExpectSameRmse(explicit_rmse, rmse);
}

TEST_F(ExportCliTest, BadInputExitsWithStatus2AndNamesFileAndLine) {
  const std::string out = FreshDir("bad");
  const std::string file = out + "/estimate.csv";
  ASSERT_EQ(RunCli("export --estimate " + Quote(Run() + "/states.csv") + " --format euroc --out " +
                   Quote(file))
                .status,
            0);
  // A NaN on line 3 (the second pose).
  std::vector<std::string> lines = ReadLines(file);
  ASSERT_GE(lines.size(), 3u);
  const std::size_t comma = lines[2].find(',');
  lines[2] = lines[2].substr(0, comma) + ",nan" + lines[2].substr(lines[2].find(',', comma + 1));
  WriteLines(file, lines);
  const std::string where = file + ":3: p_RS_R_x [m]: ";
  const CliResult ev = Evaluate(file, GroundTruth());
  EXPECT_EQ(ev.status, 2) << ev.out;
  EXPECT_NE(ev.err.find(where), std::string::npos) << ev.err;
  const CliResult ex =
      RunCli("export --estimate " + Quote(file) + " --format tum --out " + Quote(out + "/x.tum"));
  EXPECT_EQ(ex.status, 2) << ex.out;
  EXPECT_NE(ex.err.find(where), std::string::npos) << ex.err;

  // A KITTI file whose times sidecar is one line short.
  const std::string kitti = out + "/estimate.kitti";
  ASSERT_EQ(RunCli("export --estimate " + Quote(Run() + "/trajectory.tum") +
                   " --format kitti --out " + Quote(kitti))
                .status,
            0);
  std::vector<std::string> times = ReadLines(KittiTimesPath(kitti));
  times.pop_back();
  WriteLines(KittiTimesPath(kitti), times);
  const CliResult k = Evaluate(kitti, GroundTruth());
  EXPECT_EQ(k.status, 2) << k.out;
  EXPECT_NE(k.err.find(KittiTimesPath(kitti) + ":" + std::to_string(times.size()) + ": t: "),
            std::string::npos)
      << k.err;

  // Ground truth whose extension says nothing.
  const CliResult ext = Evaluate(Run() + "/trajectory.tum", out + "/groundtruth.dat");
  EXPECT_EQ(ext.status, 2);
  EXPECT_NE(ext.err.find("groundtruth.dat: extension: "), std::string::npos) << ext.err;
}

}  // namespace
}  // namespace skerry
