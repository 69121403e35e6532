/// \file
/// A long run, hour by hour: the window over a recording streamed from its files (as `skerry run`
/// does: DatasetFileStream in, RunWindow handing its estimates over, EstimateFilesWriter out),
/// printing for every hour of data the wall time, the real-time factor, the update time (median
/// and p95 over the hour's updates), the resident memory at the hour's end and the peak so far.
/// A run whose memory grows with its length shows it here; bench/long_run.sh makes the 24-hour
/// dataset (200 Hz IMU) and runs this and `skerry run` on it.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/io/measurement_stream.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/pipeline.h"

namespace skerry::bench {
namespace {

/// Resident set size now (/proc/self/statm), MiB.
double CurrentRssMiB() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  if (!(statm >> pages_total >> pages_resident)) return -1.0;
  return static_cast<double>(pages_resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) /
         (1024.0 * 1024.0);
}

struct Hour {
  int index = 0;
  double wall_s = 0.0;
  size_t updates = 0;
  double update_median_ms = 0.0;
  double update_p95_ms = 0.0;
  double rss_mib = 0.0;
  double peak_rss_mib = 0.0;
};

double Min(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

int Main(const Flags& flags) {
  if (flags.Int("cpu", -1) >= 0) PinToCpu(static_cast<int>(flags.Int("cpu", -1)));
  const std::string dataset = flags.String("dataset");
  if (dataset.empty()) throw UsageError("--dataset is required");
  const std::string out =
      flags.String("out").empty()
          ? (std::filesystem::temp_directory_path() / "skerry-long-run").string()
          : flags.String("out");
  const double hour_s = flags.Double("hour-s", 1.0);
  std::filesystem::create_directories(out);

  const Dataset header = LoadDataset(dataset, DatasetParts::kWithoutStreams);
  const EstimatorConfig config = LoadPreset(flags.String("config"));
  std::printf("# long run: dataset %s, config %s, load average %s, start RSS %.1f MiB\n",
              dataset.c_str(), config.name.c_str(), LoadAverage().c_str(), CurrentRssMiB());
  std::printf(
      "| hour | wall s | real-time factor | updates | update median ms | update p95 ms | RSS at "
      "its "
      "end MiB | peak RSS MiB |\n|---|---|---|---|---|---|---|---|\n");

  DatasetFileStream input(header);
  EstimateFilesWriter writer(out);
  std::vector<Hour> hours;
  std::vector<double> update_ms;  // this hour's
  TimeNs t0 = -1;
  int hour = 0;
  auto hour_start = std::chrono::steady_clock::now();
  const auto close_hour = [&]() {
    const auto now = std::chrono::steady_clock::now();
    Hour h;
    h.index = hour;
    h.wall_s = std::chrono::duration<double>(now - hour_start).count();
    h.updates = update_ms.size();
    h.update_median_ms = Median(update_ms);
    h.update_p95_ms = Percentile(update_ms, 95.0);
    h.rss_mib = CurrentRssMiB();
    h.peak_rss_mib = PeakRssMiB();
    std::printf("| %d | %.1f | %.0f | %zu | %.3f | %.3f | %.1f | %.1f |\n", h.index + 1, h.wall_s,
                hour_s / h.wall_s, h.updates, h.update_median_ms, h.update_p95_ms, h.rss_mib,
                h.peak_rss_mib);
    std::fflush(stdout);
    hours.push_back(h);
    update_ms.clear();
    hour_start = now;
  };
  const HistorySink sink = [&](const EstimatorHistory& piece) {
    writer.Append(piece.outputs);
    for (const UpdateStats& u : piece.stats) {
      if (t0 < 0) t0 = u.t_ns;
      while (NsToSeconds(u.t_ns - t0) >= (hour + 1) * hour_s) {
        close_hour();
        ++hour;
      }
      update_ms.push_back(u.update_ms);
    }
  };
  const WindowRun run = RunWindow(&input, header, config, {}, nullptr, {}, nullptr, sink);
  if (!update_ms.empty()) close_hour();
  writer.Commit();
  if (run.diverged) throw std::runtime_error("the run diverged: " + run.failure);

  std::printf("\n%zu keyframes over %.1f h of data in %.0f s (%.0fx real time); %zu IMU samples\n",
              writer.count(), run.data_s / 3600.0, run.wall_s, run.data_s / run.wall_s,
              run.imu_samples);
  // The last hour closes after the run (its estimator gone): the memory of the run is that of
  // the hours before it. Growth: the median RSS of the second half of those hours against that
  // of the first half (robust to one hour's allocation bump).
  if (hours.size() >= 5) {
    hours.pop_back();
    const size_t half = hours.size() / 2;
    std::vector<double> first, second, medians;
    for (size_t k = 0; k < hours.size(); ++k) {
      (k < half ? first : second).push_back(hours[k].rss_mib);
      medians.push_back(hours[k].update_median_ms);
    }
    const double grew = Median(second) - Median(first);
    std::printf(
        "RSS at the end of hours 1-%zu: %.1f..%.1f MiB; median of hours %zu-%zu %.1f MiB, of hours "
        "1-%zu %.1f MiB: %+.2f MiB (%+.3f MiB per hour); peak %.1f MiB\n",
        hours.size(), std::min(Min(first), Min(second)), std::max(Max(first), Max(second)),
        half + 1, hours.size(), Median(second), half, Median(first), grew,
        grew / static_cast<double>(hours.size() - half), hours.back().peak_rss_mib);
    std::printf("update median per hour: first %.3f, last %.3f, median of hours %.3f ms\n",
                hours.front().update_median_ms, hours.back().update_median_ms, Median(medians));
  }
  return 0;
}

}  // namespace
}  // namespace skerry::bench

int main(int argc, char** argv) {
  using skerry::bench::Flags;
  Flags flags;
  flags.Declare("dataset", "", "dataset folder (streamed: imu.csv and gnss.csv read as needed)");
  flags.Declare("config", "default", "estimator preset or YAML");
  flags.Declare("out", "", "folder for the estimate files (default: a temporary folder)");
  flags.Declare("hour-s", "3600", "the length of a reported 'hour' of data, s");
  flags.Declare("cpu", "-1", "pin to this CPU (-1: do not pin)");
  return skerry::bench::RunMain(flags, argc, argv,
                                "The window over a long recording, streamed; figures per hour",
                                [&flags]() { return skerry::bench::Main(flags); });
}
