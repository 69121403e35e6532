#include "report_command.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "report_page.h"
#include "skerry/core/input_error.h"
#include "skerry/io/atomic_file.h"

namespace skerry::cli {

namespace {

struct ReportOptions {
  std::vector<std::string> runs;
  std::string out = "report.html";
  int max_points = 4000;
};

int RunReport(const ReportOptions& o) {
  if (o.max_points < 10) {
    throw InputError(kCommandLine, 0, "--max-points", "must be at least 10");
  }
  const nlohmann::json data = ReportData(o.runs, o.max_points);
  const std::string html = RenderReportHtml(data);
  const std::filesystem::path out(o.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  WriteFileAtomically(o.out, html);
  std::printf(
      "report: %s (%zu run(s), %zu comparison(s), %.1f MB; self-contained, open it in a "
      "browser)\n",
      o.out.c_str(), data["runs"].size(), data["comparisons"].size(),
      static_cast<double>(html.size()) / 1e6);
  return 0;
}

}  // namespace

Subcommand AddReportCommand(CLI::App& app) {
  auto o = std::make_shared<ReportOptions>();
  CLI::App* cmd =
      app.add_subcommand("report",
                         "One self-contained HTML page of runs and comparisons: trajectory, errors "
                         "with 3-sigma, NEES, "
                         "heading, solver time, comparison table and plots (docs/report.md)");
  cmd->add_option("--run", o->runs, "Run folder (skerry run) or compare folder (skerry compare)")
      ->required();
  cmd->add_option("--out", o->out, "HTML file to write")->capture_default_str();
  cmd->add_option("--max-points", o->max_points, "Points per plotted series at most")
      ->capture_default_str();
  Subcommand s;
  s.app = cmd;
  s.run = [o]() { return RunReport(*o); };
  return s;
}

}  // namespace skerry::cli
