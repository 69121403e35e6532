#include "skerry/frontends/dataset_maps.h"

#include <algorithm>
#include <filesystem>

#include "skerry/core/input_error.h"
#include "skerry/io/csv_reader.h"
#include "skerry/skyline/horizon_for_track.h"

namespace skerry {

namespace {

// Where a map's keys are written, for errors that tell the user which key to set.
std::string DatasetYaml(const Dataset& data) {
  if (data.directory.empty()) return "the dataset";
  return (std::filesystem::path(data.directory) / "dataset.yaml").string();
}

}  // namespace

std::vector<Eigen::Vector3d> DatasetTrack(const Dataset& data) {
  // The best description of where the vessel went: the ground truth, else the GNSS fixes, else
  // the pose fixes (a matcher's gross fixes, 20-40 m off, must not fail a map that covers the
  // vessel).
  std::vector<Eigen::Vector3d> track;
  for (const StampedPose& p : data.groundtruth) track.push_back(p.p_w_b);
  if (!track.empty()) return track;
  for (const GnssFix& f : data.gnss_fixes) track.push_back(f.p_w);
  if (!track.empty()) return track;
  for (const PoseFix& f : data.pose_fixes) track.push_back(f.p_w);
  return track;
}

DatasetMaps LoadDatasetMaps(const Dataset& data, double margin_m, double dem_reach_m) {
  DatasetMaps maps;
  const LocalFrame frame(data.origin);
  const std::vector<Eigen::Vector3d> track = DatasetTrack(data);
  if (data.dem) {
    geo::DemOptions options(data.dem->vertical_datum == "ellipsoidal"
                                ? geo::VerticalDatum::kEllipsoidal
                                : geo::VerticalDatum::kEgm96);
    options.crs = data.dem->crs;
    options.crs_given_as = "maps.dem.crs in " + DatasetYaml(data);
    try {
      maps.dem.emplace(data.dem->path, frame, options);
    } catch (const InputError& e) {
      if (e.field() != "size") throw;
      // Too large to hold: the part the cameras can see from the track.
      options.window_enu = skyline::HorizonBox(track, std::max(dem_reach_m, margin_m));
      maps.dem.emplace(data.dem->path, frame, options);
    }
    if (!track.empty()) maps.dem->RequireCovers(track, margin_m);
  }
  if (data.orthophoto) {
    geo::OrthophotoOptions options;
    options.crs = data.orthophoto->crs;
    options.crs_given_as = "maps.orthophoto.crs in " + DatasetYaml(data);
    if (data.orthophoto->clip_fraction) options.clip_fraction = *data.orthophoto->clip_fraction;
    // The frontends read the part around the track (lidar_aerial::AerialMap): a photo of a whole
    // county is not held in memory.
    options.on_disk = true;
    maps.orthophoto.emplace(data.orthophoto->path, frame, options);
    for (const Eigen::Vector3d& p : track) {
      if (maps.orthophoto->Covers(p)) continue;
      throw InputError(data.orthophoto->path, 0, "coverage",
                       "the orthophoto does not cover the track: ENU (" + FormatDouble(p.x()) +
                           ", " + FormatDouble(p.y()) + ") m is outside its footprint");
    }
  }
  return maps;
}

}  // namespace skerry
