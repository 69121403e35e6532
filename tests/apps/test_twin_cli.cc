// skerry twin end to end: a short simulated recording's twin with its identification,
// twin.yaml, the twin dataset and the fidelity test; bad options and recordings it cannot twin
// refused with the option, file or key named.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "apps/cli_test_util.h"
#include "core/test_util.h"
#include "skerry/io/dataset.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::FreshDir;
using testing::Quote;
using testing::ReadText;
using testing::RunCli;
using testing::WriteText;

bool Contains(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

// The harbour scenario cut to its first 150 s (before its jump and outage).
std::string ShortRecording(const std::string& dir) {
  std::string yaml = ReadText(std::string(SKERRY_SOURCE_DIR) + "/config/scenarios/harbour.yaml");
  const size_t at = yaml.find("duration_s: 600");
  EXPECT_NE(at, std::string::npos);
  yaml.replace(at, 15, "duration_s: 150");
  WriteText(dir + "/short.yaml", yaml);
  const CliResult r = RunCli("simulate --scenario " + Quote(dir + "/short.yaml") + " --out " +
                             Quote(dir + "/real"));
  EXPECT_EQ(r.status, 0) << r.err;
  return dir + "/real";
}

TEST(TwinCli, MakesATwinIdentifiesItsModelsAndTestsIt) {
  const std::string dir = FreshDir("twin_cli");
  const std::string real = ShortRecording(dir);
  const CliResult r = RunCli("twin --dataset " + Quote(real) + " --out " + Quote(dir + "/twin") +
                             " --twins 3 -j 2");
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  // The identified white noise of the harbour receiver (0.3 m horizontal) and the verdict of
  // every block.
  EXPECT_TRUE(Contains(r.out, "white sigma horizontal")) << r.out;
  for (const char* block : {"position", "heading", "attitude", "velocity", "biases", "full"}) {
    EXPECT_TRUE(Contains(r.out, std::string("  ") + block)) << block << "\n" << r.out;
  }
  const std::string yaml = ReadText(dir + "/twin/twin.yaml");
  for (const char* key :
       {"\nmodel:", "\nfidelity:", "\ngnss:", "\ntiming:", "white_sigma_horizontal_m", "p_value",
        "gross_errors", "drift_detection"}) {
    EXPECT_TRUE(Contains(yaml, key)) << key;
  }
  // The twin is a dataset at the recording's stamps, with its truth.
  const Dataset twin = LoadDataset(dir + "/twin");
  const Dataset recording = LoadDataset(real);
  EXPECT_FALSE(twin.truth_states.empty());
  // The twin covers the batch's span: the recording's fixes from its first keyframe on.
  ASSERT_GE(twin.gnss_fixes.size() + 4, recording.gnss_fixes.size());
  const size_t skipped = recording.gnss_fixes.size() - twin.gnss_fixes.size();
  for (size_t i = 0; i < twin.gnss_fixes.size(); i += 50) {
    EXPECT_EQ(twin.gnss_fixes[i].t_ns, recording.gnss_fixes[i + skipped].t_ns);
  }
  EXPECT_TRUE(fs::exists(dir + "/twin/identification/gnss_residuals.csv"));
  EXPECT_TRUE(fs::exists(dir + "/twin/fidelity/real/states.csv"));
  EXPECT_TRUE(fs::exists(dir + "/twin/fidelity/twin-3/states.csv"));
  EXPECT_TRUE(fs::exists(dir + "/twin/fidelity/over_time.csv"));
  // The recording's run and a twin's side by side in the report, against the batch truth.
  const CliResult report =
      RunCli("report --run " + Quote(dir + "/twin/fidelity/real") + " --run " +
             Quote(dir + "/twin/fidelity/twin-1") + " --out " + Quote(dir + "/report.html"));
  EXPECT_EQ(report.status, 0) << report.err;
  const std::string html = ReadText(dir + "/report.html");
  EXPECT_TRUE(Contains(html, "twin of seed 1")) << "the twin's run is named in the report";

  // Its model read back (--model) gives the same twin, seed for seed.
  const CliResult again =
      RunCli("twin --dataset " + Quote(real) + " --out " + Quote(dir + "/again") +
             " --twins 0 --no-drift-limit --model " + Quote(dir + "/twin/twin.yaml"));
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_TRUE(ReadText(dir + "/again/gnss.csv") == ReadText(dir + "/twin/gnss.csv"));
  EXPECT_TRUE(ReadText(dir + "/again/imu.csv") == ReadText(dir + "/twin/imu.csv"));
  // An existing twin is not replaced without --overwrite.
  const CliResult refused =
      RunCli("twin --dataset " + Quote(real) + " --out " + Quote(dir + "/twin") + " --twins 0");
  EXPECT_EQ(refused.status, 2);
}

// A real marine log without IMU: its twin re-simulates the GNSS along a track through the fixes
// and is judged on the fixes' statistics.
TEST(TwinCli, TwinsTheGnssOfALogWithoutImu) {
  const std::string log =
      std::string(SKERRY_SHARED_DATA_DIR) + "/boat/furuno-130842-wide-turn.si.jsonl.gz";
  if (!fs::exists(log)) GTEST_SKIP() << log << " missing";
  const std::string dir = FreshDir("twin_cli_boat");
  ASSERT_EQ(
      RunCli("import --format nmea2000 " + Quote(log) + " --out " + Quote(dir + "/boat")).status,
      0);
  const CliResult r = RunCli("twin --dataset " + Quote(dir + "/boat") + " --out " +
                             Quote(dir + "/twin") + " --twins 4");
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  EXPECT_TRUE(Contains(r.out, "has no IMU")) << r.out;
  EXPECT_TRUE(Contains(r.out, "lag-1 correlation of residuals")) << r.out;
  const Dataset twin = LoadDataset(dir + "/twin");
  const Dataset boat = LoadDataset(dir + "/boat");
  EXPECT_FALSE(twin.has_imu);
  EXPECT_EQ(twin.gnss_fixes.size(), boat.gnss_fixes.size());  // the track spans every fix
  const std::string yaml = ReadText(dir + "/twin/twin.yaml");
  EXPECT_TRUE(Contains(yaml, "\ntrack:")) << yaml;
  EXPECT_TRUE(Contains(yaml, "\ngnss_statistics:")) << yaml;
}

TEST(TwinCli, RefusesWhatItCannotTwin) {
  const std::string dir = FreshDir("twin_cli_bad");
  const std::string real = ShortRecording(dir);
  CliResult r =
      RunCli("twin --dataset " + Quote(real) + " --out " + Quote(dir + "/t1") + " --twins 1");
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Contains(r.err, "--twins")) << r.err;
  // A rest threshold that is not a duration (nan passed every comparison as "no rest").
  for (const char* bad : {"nan", "0", "1e300"}) {
    r = RunCli("twin --dataset " + Quote(real) + " --out " + Quote(dir + "/t0") +
               " --twins 0 --min-rest " + bad);
    EXPECT_EQ(r.status, 2) << bad;
    EXPECT_TRUE(Contains(r.err, "--min-rest")) << r.err;
  }
  // A seed that is not one (CLI11 alone made -1 a seed of 2^64 - 1).
  for (const char* bad : {"-1", "18446744073709551616"}) {
    r = RunCli("twin --dataset " + Quote(real) + " --out " + Quote(dir + "/t0") +
               " --twins 0 --seed " + bad);
    EXPECT_EQ(r.status, 2) << bad;
    EXPECT_TRUE(Contains(r.err, "--seed: must be a whole number from 0 to 18446744073709551615"))
        << r.err;
  }
  // A configuration with a key changed to a bad value (config_variant.h): the option and the key.
  r = RunCli("twin --dataset " + Quote(real) + " --out " + Quote(dir + "/t0") +
             " --twins 0 --config default,solver.max_iterations=many");
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Contains(r.err, "--config solver.max_iterations")) << r.err;
  // A model file with a key missing: the file and the key.
  WriteText(dir + "/bad.yaml", "model:\n  imu: {}\n  gnss: {}\n");
  r = RunCli("twin --dataset " + Quote(real) + " --out " + Quote(dir + "/t2") +
             " --twins 0 --model " + Quote(dir + "/bad.yaml"));
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(Contains(r.err, "bad.yaml")) << r.err;
  EXPECT_TRUE(Contains(r.err, "model.imu.gyro_noise_density_rad_s_sqrt_hz")) << r.err;
  // A recording without GNSS (EuRoC's IMU alone): no receiver model to identify.
  const std::string euroc = std::string(SKERRY_SHARED_DATA_DIR) + "/euroc_v1_01";
  if (fs::exists(euroc)) {
    ASSERT_EQ(
        RunCli("import --format euroc --input " + Quote(euroc) + " --out " + Quote(dir + "/euroc"))
            .status,
        0);
    r = RunCli("twin --dataset " + Quote(dir + "/euroc") + " --out " + Quote(dir + "/t3"));
    EXPECT_EQ(r.status, 2);
    EXPECT_TRUE(Contains(r.err, "sensors.gnss")) << r.err;
  }
}

}  // namespace
}  // namespace skerry
