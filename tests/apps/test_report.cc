// `skerry report` end to end: real runs and a real comparison, the page rendered in headless
// Chromium, and the page's own self-check read back from the DOM: every chart canvas must
// have data-coloured pixels in its plot area (not only exist). Skipped without Chromium.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "apps/cli_test_util.h"
#include "core/test_util.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::FreshDir;
using testing::Quote;
using testing::ReadText;
using testing::RunCli;
using testing::ShortScenarioYaml;
using testing::WriteText;

const char* kChromium = "/usr/bin/chromium";

/// Renders `html` headless; `mode` is "--dump-dom" (the DOM goes to `out`) or
/// "--screenshot=FILE".
int Chromium(const std::string& html, const std::string& mode, const std::string& out) {
  const std::string profile = FreshDir("chromium-profile");
  const std::string cmd = std::string("timeout 180 ") + kChromium +
                          " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
                          " --disable-background-networking --disable-component-update"
                          " --disable-sync --hide-scrollbars --user-data-dir=" +
                          Quote(profile) + " --window-size=1400,4200 --virtual-time-budget=10000 " +
                          mode + " " + Quote("file://" + html) + " > " + Quote(out) +
                          " 2> /dev/null";
  return std::system(cmd.c_str());
}

struct Painted {
  int drawn = -1;
  int painted = -1;
  std::vector<int> per_chart;
};

Painted ReadSelfCheck(const std::string& dom) {
  Painted p;
  std::smatch m;
  if (std::regex_search(dom, m, std::regex("data-charts-drawn=\"([0-9]+)\""))) {
    p.drawn = std::stoi(m[1]);
  }
  if (std::regex_search(dom, m, std::regex("data-charts-painted=\"([0-9]+)\""))) {
    p.painted = std::stoi(m[1]);
  }
  const std::regex each("data-painted=\"([0-9]+)\"");
  for (auto it = std::sregex_iterator(dom.begin(), dom.end(), each); it != std::sregex_iterator();
       ++it) {
    p.per_chart.push_back(std::stoi((*it)[1]));
  }
  return p;
}

/// The page loads nothing: no http(s) URL in a src or href.
void ExpectSelfContained(const std::string& html) {
  EXPECT_FALSE(std::regex_search(html, std::regex("(src|href)\\s*=\\s*[\"']?https?:")));
  EXPECT_EQ(html.find("<link"), std::string::npos);
}

class ReportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kChromium)) GTEST_SKIP() << "chromium is not installed (scripts/setup.sh)";
    dir_ = FreshDir("report");
    scenario_ = dir_ + "/scenario.yaml";
    WriteText(scenario_,
              ShortScenarioYaml(140.0, "harbour-short",
                                "  jumps:\n"
                                "    - {start_s: 50, duration_s: 15, offset_enu_m: [14.5, 0, 0]}\n"
                                "  outages:\n"
                                "    - {start_s: 90, duration_s: 30}\n"));
  }
  std::string dir_;
  std::string scenario_;
};

TEST_F(ReportTest, SingleRunIsDrawn) {
  const std::string data = dir_ + "/data", run = dir_ + "/run", html = dir_ + "/run.html";
  ASSERT_EQ(
      RunCli("simulate --scenario " + Quote(scenario_) + " --seed 3 --out " + Quote(data)).status,
      0);
  ASSERT_EQ(RunCli("run -q --dataset " + Quote(data) + " --out " + Quote(run)).status, 0);
  const CliResult r = RunCli("report --run " + Quote(run) + " --out " + Quote(html));
  ASSERT_EQ(r.status, 0) << r.err;
  ExpectSelfContained(ReadText(html));

  ASSERT_EQ(Chromium(html, "--dump-dom", dir_ + "/dom.html"), 0);
  const Painted p = ReadSelfCheck(ReadText(dir_ + "/dom.html"));
  // Map, horizontal error, NEES, heading error, solver time.
  EXPECT_EQ(p.drawn, 5);
  EXPECT_EQ(p.painted, 5);
  ASSERT_EQ(p.per_chart.size(), 5u);
  for (int n : p.per_chart) EXPECT_GT(n, 500);

  ASSERT_EQ(Chromium(html, "--screenshot=" + Quote(dir_ + "/run.png"), dir_ + "/shot.log"), 0);
  ASSERT_TRUE(fs::exists(dir_ + "/run.png"));
  EXPECT_GT(fs::file_size(dir_ + "/run.png"), 50000u);
}

TEST_F(ReportTest, ComparisonIsDrawn) {
  const std::string cmp = dir_ + "/compare", html = dir_ + "/compare.html";
  WriteText(dir_ + "/bad.yaml",
            "name: bad\nwindow_keyframes: 3\ngnss: {loss: none, gate_probability: 0}\n");
  CliResult r =
      RunCli("compare -q --dataset " + Quote(scenario_) + " --seeds 2 --config default --config " +
             Quote(dir_ + "/bad.yaml") + " --out " + Quote(cmp));
  ASSERT_EQ(r.status, 0) << r.err;
  r = RunCli("report --run " + Quote(cmp) + " --out " + Quote(html));
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string page = ReadText(html);
  ExpectSelfContained(page);
  EXPECT_NE(page.find("Chart.js v3"), std::string::npos);  // inlined, not fetched

  ASSERT_EQ(Chromium(html, "--dump-dom", dir_ + "/dom.html"), 0);
  const std::string dom = ReadText(dir_ + "/dom.html");
  const Painted p = ReadSelfCheck(dom);
  // 4 bar charts, 2 box plots, 4 HED-over-time charts, 5 run charts.
  EXPECT_EQ(p.drawn, 15);
  EXPECT_EQ(p.painted, 15);
  ASSERT_EQ(p.per_chart.size(), 15u);
  for (int n : p.per_chart) EXPECT_GT(n, 200);
  // The table: both configurations, the reference marked.
  EXPECT_NE(dom.find("default (reference)"), std::string::npos);
  EXPECT_NE(dom.find(">bad<"), std::string::npos);
}

// Strings from a dataset (its name), a configuration (its name) and the file system (the run
// folder's path) with markup and script in them: the page shows them as text, none of them runs,
// and the page still draws (an "<!--<script" in the data used to swallow the page).
TEST_F(ReportTest, MarkupInNamesIsShownAndNeverRuns) {
  // Every payload marks the page if it runs: a script, an event handler, an SVG onload.
  const std::string scenario = dir_ + "/markup.yaml";
  std::string yaml = ReadText(scenario_);
  const size_t at = yaml.find("name: harbour-short");
  ASSERT_NE(at, std::string::npos);
  yaml.replace(at, std::string("name: harbour-short").size(),
               "name: '<img src=x onerror=document.body.dataset.pwnedname=1><script>"
               "document.body.dataset.pwnedscript=1</script><!--<script>'");
  WriteText(scenario, yaml);
  WriteText(dir_ + "/markup-config.yaml",
            "name: '<svg onload=document.body.dataset.pwnedconfig=1>&amp;'\n");
  const std::string data = dir_ + "/data";
  const std::string run = dir_ + "/<img src=x onerror=document.body.dataset.pwnedpath=1>/run";
  const std::string html = dir_ + "/markup.html";
  ASSERT_EQ(
      RunCli("simulate --scenario " + Quote(scenario) + " --seed 3 --out " + Quote(data)).status,
      0);
  fs::create_directories(fs::path(run).parent_path());
  ASSERT_EQ(RunCli("run -q --dataset " + Quote(data) + " --config " +
                   Quote(dir_ + "/markup-config.yaml") + " --out " + Quote(run))
                .status,
            0);
  const CliResult r = RunCli("report --run " + Quote(run) + " --out " + Quote(html));
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string page = ReadText(html);
  EXPECT_EQ(page.find("<img src=x"), std::string::npos) << "markup written raw into the page";
  EXPECT_EQ(page.find("<svg onload"), std::string::npos);

  ASSERT_EQ(Chromium(html, "--dump-dom", dir_ + "/dom.html"), 0);
  const std::string dom = ReadText(dir_ + "/dom.html");
  EXPECT_EQ(dom.find("data-pwned"), std::string::npos) << "a payload ran";
  // Shown as text: the DOM serialises it escaped.
  EXPECT_NE(dom.find("&lt;img src=x onerror=document.body.dataset.pwnedname=1&gt;"),
            std::string::npos);
  EXPECT_NE(dom.find("&lt;svg onload=document.body.dataset.pwnedconfig=1&gt;&amp;amp;"),
            std::string::npos);
  const Painted p = ReadSelfCheck(dom);
  EXPECT_EQ(p.drawn, 5) << "the page did not draw";
  EXPECT_EQ(p.painted, 5);
}

// A twin folder (skerry twin): the recording's run beside a twin's, the fidelity test per block
// against the twins' spread, and the models identified, on the sheet and in the twin.
TEST_F(ReportTest, TwinIsDrawn) {
  const std::string data = dir_ + "/data", twin = dir_ + "/twin", html = dir_ + "/twin.html";
  WriteText(dir_ + "/quiet.yaml", ShortScenarioYaml(140.0, "harbour-quiet", ""));
  ASSERT_EQ(RunCli("simulate --scenario " + Quote(dir_ + "/quiet.yaml") + " --seed 5 --out " +
                   Quote(data))
                .status,
            0);
  CliResult r = RunCli("twin -q --dataset " + Quote(data) + " --out " + Quote(twin) +
                       " --twins 2 -j 2 --no-drift-limit");
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  r = RunCli("report --run " + Quote(twin) + " --out " + Quote(html));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("2 run(s)"), std::string::npos) << r.out;
  ExpectSelfContained(ReadText(html));

  ASSERT_EQ(Chromium(html, "--dump-dom", dir_ + "/dom.html"), 0);
  const std::string dom = ReadText(dir_ + "/dom.html");
  const Painted p = ReadSelfCheck(dom);
  // Real vs twin per block, the distance over time; the two runs' map, horizontal error, NEES and
  // heading error against the twin's truth (the test's runs keep no solver times).
  EXPECT_EQ(p.drawn, 6);
  EXPECT_EQ(p.painted, 6);
  for (int n : p.per_chart) EXPECT_GT(n, 200);
  EXPECT_NE(dom.find("Digital twin of"), std::string::npos);
  for (const char* block :
       {">position<", ">heading<", ">attitude<", ">velocity<", ">biases<", ">full<"}) {
    EXPECT_NE(dom.find(block), std::string::npos) << block;
  }
  // Every block has a verdict; the models table names the receiver's identified noise.
  const std::regex verdicts(">(indistinguishable|twin differs)<");
  EXPECT_EQ(
      std::distance(std::sregex_iterator(dom.begin(), dom.end(), verdicts), std::sregex_iterator()),
      6);
  EXPECT_NE(dom.find("gnss.white_sigma_horizontal_m"), std::string::npos);
  EXPECT_NE(dom.find("imu.gyro_noise_density_rad_s_sqrt_hz"), std::string::npos);
  EXPECT_NE(dom.find(">twin of seed 1<"), std::string::npos);
}

// A twin.yaml that is not one is refused by name.
TEST_F(ReportTest, AMalformedTwinYamlIsAnError) {
  const std::string twin = dir_ + "/not-a-twin";
  fs::create_directories(twin);
  WriteText(twin + "/twin.yaml", "twin: [1, 2\n");
  CliResult r = RunCli("report --run " + Quote(twin) + " --out " + Quote(dir_ + "/x.html"));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("twin.yaml"), std::string::npos) << r.err;
  WriteText(twin + "/twin.yaml", "model: {}\n");
  r = RunCli("report --run " + Quote(twin) + " --out " + Quote(dir_ + "/x.html"));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("twin.yaml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("twin"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ + "/x.html"));
}

TEST_F(ReportTest, AFolderThatIsNeitherIsAnError) {
  const CliResult r = RunCli("report --run " + Quote(dir_) + " --out " + Quote(dir_ + "/x.html"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--run"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ + "/x.html"));
}

}  // namespace
}  // namespace skerry
