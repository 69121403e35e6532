// Prior work's pipeline (its planar EKF fed by GNSS and by its correlation-and-swarm matcher on
// every scan, frontends/lidar_aerial/baseline_run.h) on a dataset with a LiDAR and an orthophoto,
// for the side-by-side of bench/lidar/harbour_runs.sh: writes the filter's pose after every
// update as a TUM trajectory (planar: height 0, heading only) and prints the matcher's counts and
// time per match.
//   skerry_harbour_baseline --dataset DIR --out DIR [--config PRESET] [--match-every N]
// --out DIR gets trajectory.tum and baseline.json (counts, seconds per match).

#include <Eigen/Geometry>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "bench_util.h"
#include "skerry/frontends/dataset_maps.h"
#include "skerry/io/dataset.h"
#include "skerry/lidar_aerial/baseline_run.h"
#include "skerry/solvers/estimator_config.h"

namespace skerry::bench {
namespace {

int Main(const Flags& flags) {
  const std::string dataset = flags.String("dataset"), out = flags.String("out");
  if (dataset.empty() || out.empty()) throw UsageError("--dataset and --out are required");
  const std::string preset = flags.String("config");
  const int match_every = static_cast<int>(flags.Int("match-every", 1));
  const Dataset data = LoadDataset(dataset);
  const EstimatorConfig config = LoadPreset(preset);
  const DatasetMaps maps = LoadDatasetMaps(data);
  if (!maps.orthophoto) throw UsageError(dataset + ": no maps.orthophoto");
  lidar_aerial::baseline::BaselineRunOptions o;
  o.match_every = match_every;
  o.min_height_m = config.lidar_aerial.min_height_m;
  const auto& lo = config.lidar_aerial.hull_min_b_m;
  const auto& hi = config.lidar_aerial.hull_max_b_m;
  if (hi[0] > lo[0] && hi[1] > lo[1] && hi[2] > lo[2]) {
    o.hull_b = Eigen::AlignedBox3d(Eigen::Vector3d(lo[0], lo[1], lo[2]),
                                   Eigen::Vector3d(hi[0], hi[1], hi[2]));
  }
  // Prior work's map: the photo at its own pixel, around the track with a tile's margin.
  Eigen::AlignedBox2d box;
  for (const Eigen::Vector3d& p : DatasetTrack(data)) box.extend(p.head<2>().eval());
  box.min().array() -= o.matcher.tile_m;
  box.max().array() += o.matcher.tile_m;
  box = box.intersection(maps.orthophoto->footprint_box_enu());
  lidar_aerial::AerialMapOptions mo;
  mo.resolution_m = o.matcher.cell_m;
  const lidar_aerial::AerialMap map(*maps.orthophoto, box, mo);
  const auto t0 = std::chrono::steady_clock::now();
  const lidar_aerial::baseline::BaselineRun run = lidar_aerial::baseline::RunBaseline(data, map, o);
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::filesystem::create_directories(out);
  {
    std::ofstream tum(out + "/trajectory.tum");
    tum << "# prior work's planar EKF (bench/harbour_baseline.cc): t x y z qx qy qz qw\n";
    char line[256];
    for (const auto& e : run.estimates) {
      const Eigen::Quaterniond q(Eigen::AngleAxisd(e.x(4), Eigen::Vector3d::UnitZ()));
      std::snprintf(line, sizeof(line), "%.9f %.6f %.6f 0 %.9f %.9f %.9f %.9f\n",
                    NsToSeconds(e.t_ns), e.x(0), e.x(1), q.x(), q.y(), q.z(), q.w());
      tum << line;
    }
  }
  const double per_match = run.matches > 0 ? run.match_s / run.matches : 0.0;
  {
    std::ofstream json(out + "/baseline.json");
    json << "{\"scans\": " << run.scans << ", \"matches\": " << run.matches
         << ", \"accepted\": " << run.accepted << ", \"gated\": " << run.gated
         << ", \"invalid\": " << run.invalid << ", \"seconds_per_match\": " << per_match
         << ", \"wall_s\": " << wall_s << "}\n";
  }
  std::printf("%s: %d scans, %d matches (%d accepted, %d gated, %d invalid), %.2f s per match\n",
              data.name.c_str(), run.scans, run.matches, run.accepted, run.gated, run.invalid,
              per_match);
  return 0;
}

}  // namespace
}  // namespace skerry::bench

int main(int argc, char** argv) {
  skerry::bench::Flags flags;
  flags.Declare("dataset", "", "a dataset with a LiDAR, an orthophoto and ground truth");
  flags.Declare("out", "", "output folder (trajectory.tum, baseline.json)");
  flags.Declare("config", "lidar-harbour", "estimator preset or YAML file (water cut, hull box)");
  flags.Declare("match-every", "1", "match every this many scans");
  return skerry::bench::RunMain(flags, argc, argv,
                                "Prior work's planar EKF and matcher on a LiDAR dataset",
                                [&flags]() { return skerry::bench::Main(flags); });
}
