#pragma once
/// \file
/// What the skyline bench tools that work at the ground truth read first: a camera dataset
/// without its streams, checked for the camera and the ground truth they need, and the horizon
/// predictor the skyline frontend would build from its DEM (skyline::HorizonForTrack).

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "skerry/frontends/dataset_maps.h"
#include "skerry/io/dataset.h"
#include "skerry/skyline/horizon_for_track.h"
#include "skerry/solvers/estimator_config.h"

namespace skerry::bench {

struct SkylineTruthData {
  Dataset data;
  std::shared_ptr<const skyline::HorizonPredictor> horizon;
};

/// nullopt, with a message naming `dir` on stderr, when the dataset has no camera
/// `camera_index`, no ground truth or no maps.dem; throws as LoadDataset and LoadDatasetMaps do.
inline std::optional<SkylineTruthData> LoadSkylineTruthData(const std::string& dir,
                                                            const SkylineConfig& config,
                                                            size_t camera_index) {
  SkylineTruthData out;
  out.data = LoadDataset(dir, DatasetParts::kWithoutStreams);
  if (camera_index >= out.data.cameras.size() || out.data.groundtruth.empty()) {
    std::fprintf(stderr, "%s: needs camera %zu and a ground truth\n", dir.c_str(), camera_index);
    return std::nullopt;
  }
  const DatasetMaps maps = LoadDatasetMaps(out.data);
  if (!maps.dem) {
    std::fprintf(stderr, "%s: no maps.dem\n", dir.c_str());
    return std::nullopt;
  }
  out.horizon = skyline::HorizonForTrack(*maps.dem, DatasetTrack(out.data), config);
  return out;
}

}  // namespace skerry::bench
