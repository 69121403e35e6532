// skerry: the command-line front of the estimation engine. A thin main: options are parsed
// here, the work is in src/commands.cc, bad input surfaces as InputError (exit status 2).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <limits>
#include <vector>

#include "skerry/core/input_error.h"
#include "skerry/core/time.h"
#include "src/align_aerial_command.h"
#include "src/commands.h"
#include "src/compare_command.h"
#include "src/export_command.h"
#include "src/finite_number.h"
#include "src/report_command.h"
#include "src/seed_number.h"
#include "src/twin_command.h"

int main(int argc, char** argv) {
  using namespace skerry::cli;
  CLI::App app{
      "skerry: factor-graph navigation for vessels (IMU, GNSS, a camera's skyline against a DEM, "
      "LiDAR against an aerial image)"};
  app.require_subcommand(1);
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "Debug logging");

  SimulateOptions sim;
  CLI::App* simulate = app.add_subcommand("simulate", "Simulate a vessel scenario into a dataset");
  simulate->add_option("--scenario", sim.scenario, "Built-in scenario name or YAML file")
      ->capture_default_str();
  simulate->add_option("--seed", sim.seed, "Random seed (default: the scenario's)")
      ->check(SeedNumber());
  simulate->add_option("--out", sim.out, "Output dataset folder")->required();
  simulate->add_flag("--matched", sim.matched,
                     "Leave out the errors skerry does not model (scale factor, misalignment, "
                     "Gauss-Markov bias, second GNSS process, multipath, latency, jitter) and "
                     "use the GNSS drift of --matched-config");
  simulate
      ->add_option("--matched-config", sim.matched_config,
                   "--matched: the estimator configuration to match (preset or YAML)")
      ->capture_default_str();
  simulate->add_option("--earth", sim.earth, "wgs84 or flat: the world to simulate")
      ->check(CLI::IsMember({"wgs84", "flat"}));
  simulate
      ->add_option("--dem-error", sim.dem_error_m,
                   "The DEM's own height error in the world the cameras see, sigma in m (the "
                   "map the estimator is given stays as it is; docs/simulator.md)")
      ->check(FiniteNumber(0.0));
  simulate
      ->add_option("--dem-error-length", sim.dem_error_length_m,
                   "Its correlation length on the ground, m (default: the scenario's, 1000)")
      ->check(FiniteNumber(0.0, std::numeric_limits<double>::infinity(), true));
  simulate
      ->add_option("--dem-relief", sim.dem_relief,
                   "Relief finer than the DEM's cell in the world the cameras see, the gain of "
                   "the deconvolution that gives it back (1: crests as far above the raster as "
                   "real terrain's above its block means; 0: none; docs/simulator.md)")
      ->check(FiniteNumber(0.0, 10.0));
  simulate->add_flag("--overwrite", sim.overwrite, "Replace a dataset already in --out");
  simulate
      ->add_option("-j,--jobs", sim.jobs,
                   "Threads rendering camera frames (default: every core); the dataset is the "
                   "same whatever their number")
      ->check(CLI::NonNegativeNumber);

  EstimateOptions run_opts;
  CLI::App* run = app.add_subcommand("run", "Sliding-window estimation, in time order (live)");
  EstimateOptions smooth_opts;
  CLI::App* smooth = app.add_subcommand("smooth", "Batch smoothing of the whole trajectory");
  for (auto [cmd, opts] : {std::make_pair(run, &run_opts), std::make_pair(smooth, &smooth_opts)}) {
    cmd->add_option("--dataset", opts->dataset, "Dataset folder (docs/dataset-format.md)")
        ->required();
    cmd->add_option("--config", opts->config, "Preset name (config/presets) or YAML file")
        ->capture_default_str();
    cmd->add_option("--set", opts->set,
                    "KEY=VALUE: one key of the configuration changed, the others kept (e.g. "
                    "--set skyline.dem_spacing_m=63); repeat for more")
        ->expected(1)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    cmd->add_option("--out", opts->out, "Output folder")->required();
    cmd->add_flag("-q,--quiet", opts->quiet, "No progress or summary on the terminal");
    cmd->add_flag("--overwrite", opts->overwrite, "Replace results already in --out");
  }
  smooth->add_option("--until", smooth_opts.until_s,
                     "Only the data up to this time (s): the batch's last keyframe is then the "
                     "best estimate a live estimator could make at that time");
  run->add_option("-j,--jobs", run_opts.jobs,
                  "Threads a camera frame's horizon is traced on (default: the configuration's "
                  "skyline.threads); the estimate is the same whatever their number")
      ->check(CLI::Range(1, 256));
  smooth
      ->add_option("-j,--jobs", smooth_opts.jobs,
                   "Threads of the batch solve and of the initial pass's camera frames (default: "
                   "the configuration's batch_solver.num_threads and skyline.threads); the "
                   "estimate is the same whatever their number")
      ->check(CLI::Range(1, 256));

  EvaluateOptions eval;
  CLI::App* evaluate =
      app.add_subcommand("evaluate", "Accuracy of an estimate against ground truth");
  evaluate
      ->add_option("--estimate", eval.estimate,
                   "states.csv or a trajectory (.tum/.txt TUM, .kitti KITTI, .csv EuRoC)")
      ->required();
  evaluate
      ->add_option("--groundtruth", eval.groundtruth,
                   "Ground-truth trajectory (.tum/.txt TUM, .kitti KITTI, .csv EuRoC)")
      ->required();
  evaluate
      ->add_option("--estimate-format", eval.estimate_format,
                   "tum, kitti or euroc (default: by extension)")
      ->check(CLI::IsMember({"tum", "kitti", "euroc"}));
  evaluate
      ->add_option("--groundtruth-format", eval.groundtruth_format,
                   "tum, kitti or euroc (default: by extension)")
      ->check(CLI::IsMember({"tum", "kitti", "euroc"}));
  evaluate->add_option("--events", eval.events, "events.csv of a simulated dataset");
  evaluate->add_option("--json", eval.json_out, "Write the figures as JSON here");
  evaluate->add_option("--rpe-delta", eval.rpe_delta_s, "RPE interval, s")
      ->capture_default_str()
      ->check(FiniteNumber(0.0, skerry::kMaxDurationS, true));
  evaluate->add_option("--from", eval.from_s,
                       "Also summarise the span from this time (s; e.g. a GNSS outage's start)");
  evaluate->add_option("--to", eval.to_s, "... to this time (s; default: the last estimate)");
  evaluate
      ->add_option("--edge", eval.edge_s,
                   "Seconds at the span's start and end whose mean errors are compared (growth)")
      ->capture_default_str()
      ->check(FiniteNumber(0.0, skerry::kMaxDurationS, true));

  ImportOptions imp;
  CLI::App* import = app.add_subcommand(
      "import",
      "Convert EuRoC or Husky recordings, or NMEA 0183 / NMEA 2000 (canboat JSON) marine logs, to "
      "a dataset");
  import
      ->add_option("--format", imp.format,
                   "euroc, husky, nmea0183 (a log of sentences) or nmea2000 (canboat analyzer "
                   "-json -si lines); logs may be gzip-compressed")
      ->required();
  import
      ->add_option("input,--input", imp.input,
                   "Recording folder (euroc, husky) or log file (nmea0183, nmea2000)")
      ->required();
  import->add_option("--out", imp.out, "Output dataset folder")->required();
  import->add_option("--fixes-rate", imp.fixes_rate_hz,
                     "EuRoC: make position fixes from the ground truth at this rate (Hz)");
  import->add_option("--fixes-sigma", imp.fixes_sigma_m, "EuRoC: their noise, m")
      ->capture_default_str();
  import->add_option("--seed", imp.seed, "EuRoC: noise seed")
      ->check(SeedNumber())
      ->capture_default_str();
  import->add_option("--source", imp.sources,
                     "NMEA: KIND=SOURCE, the source to keep for fix, heading, course, attitude "
                     "or rate_of_turn (e.g. fix=25; default: the one with the most records)");
  import->add_flag("--overwrite", imp.overwrite, "Replace a dataset already in --out");

  // Commands that keep their options in their own file.
  const std::vector<Subcommand> more = {AddExportCommand(app),      AddCompareCommand(app),
                                        AddFidelityCommand(app),    AddReportCommand(app),
                                        AddAlignAerialCommand(app), AddTwinCommand(app)};

  // A command line CLI11 refuses (an unknown option, a value out of its range) is bad input
  // like any other: exit status 2, as the README says. --help and --version stay 0.
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::warn);
  try {
    if (*simulate) return Simulate(sim);
    if (*run) return Run(run_opts);
    if (*smooth) return Smooth(smooth_opts);
    if (*evaluate) return Evaluate(eval);
    if (*import) return Import(imp);
    for (const Subcommand& command : more) {
      if (*command.app) return command.run();
    }
  } catch (const skerry::InputError& e) {
    std::cerr << "skerry: error: " << e.what() << "\n";
    return 2;
  } catch (const EstimatorDiverged& e) {
    std::cerr << "skerry: error: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "skerry: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
