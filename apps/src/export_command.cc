#include "export_command.h"

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "skerry/io/estimate_io.h"
#include "skerry/io/trajectory_formats.h"

namespace skerry::cli {

namespace {

struct ExportOptions {
  std::string estimate;      ///< a run's states.csv, or a trajectory file (TUM, KITTI, EuRoC)
  std::string input_format;  ///< empty: from the extension of `estimate`
  std::string format;        ///< tum | kitti | euroc
  std::string out;
};

int Export(const ExportOptions& o) {
  const TrajectoryFormat out_format = ParseTrajectoryFormat(o.format);
  std::size_t count = 0;
  std::string what;
  if (o.input_format.empty() && IsStatesCsv(o.estimate)) {
    // A run's states.csv: EuRoC export keeps velocity and biases as ASL's extra columns.
    const std::vector<EstimateRecord> records = ReadEstimate(o.estimate);
    WriteTrajectory(o.out, records, out_format);
    count = records.size();
    what = out_format == TrajectoryFormat::kEuroc ? "states (pose, velocity, biases)" : "poses";
  } else {
    const std::vector<StampedPose> poses =
        ReadTrajectory(o.estimate, TrajectoryFormatFor(o.estimate, o.input_format));
    WriteTrajectory(o.out, poses, out_format);
    count = poses.size();
    what = "poses";
  }
  std::printf("exported %zu %s from %s to %s (%s)\n", count, what.c_str(), o.estimate.c_str(),
              o.out.c_str(), TrajectoryFormatName(out_format).c_str());
  if (out_format == TrajectoryFormat::kKitti) {
    std::printf("  times in %s (one per line, s)\n", KittiTimesPath(o.out).c_str());
  }
  return 0;
}

}  // namespace

Subcommand AddExportCommand(CLI::App& app) {
  auto options = std::make_shared<ExportOptions>();
  const std::vector<std::string> formats = {"tum", "kitti", "euroc"};
  Subcommand s;
  s.app = app.add_subcommand(
      "export", "Write an estimate as a TUM, KITTI or EuRoC trajectory (the formats evo reads)");
  s.app
      ->add_option("--estimate", options->estimate,
                   "A run's states.csv, or a trajectory (.tum/.txt, .kitti, .csv EuRoC)")
      ->required();
  s.app
      ->add_option("--input-format", options->input_format,
                   "Format of --estimate (default: from its extension)")
      ->check(CLI::IsMember(formats));
  s.app->add_option("--format", options->format, "Output format")
      ->required()
      ->check(CLI::IsMember(formats));
  s.app->add_option("--out", options->out, "Output file (KITTI: also <out>.times)")->required();
  s.run = [options]() { return Export(*options); };
  return s;
}

}  // namespace skerry::cli
