#pragma once
/// \file
/// twin.yaml: every parameter `skerry twin` identified, each as {value, sigma, identified}, the
/// recording's own (datasheet) model beside them, the streams' timing, the model the twin was
/// simulated with (`model:`, which `skerry twin --model` reads back), and, when run, the
/// twin-vs-recording fidelity test. Layout: docs/twin.md.

#include <cstdint>
#include <string>
#include <vector>

#include "skerry/io/dataset.h"
#include "skerry/sim/twin.h"
#include "skerry/twin/gnss_statistics.h"
#include "skerry/twin/gnss_track.h"
#include "skerry/twin/twin_calibration.h"
#include "skerry/twin/twin_fidelity.h"
#include "skerry/twin/twin_identification.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace skerry {

struct TwinProvenance {
  std::string recording;  ///< the real dataset's folder
  std::string config;     ///< the estimator configuration of the batch and the runs
  int truth_keyframes = 0;
  double knot_s = 0.0;
  double truth_start_s = 0.0, truth_end_s = 0.0;  ///< stamps of the truth's span, s
  std::uint64_t seed = 1;
  std::string model_source = "identified";  ///< or the file given with --model
};

/// Writes twin.yaml (atomically). `fidelity` (of id.model), `before` (of the identified model,
/// when calibrated), `calibration` and `identified` may be null (not run); `track` and
/// `gnss_statistics` are a recording without IMU's truth and test.
void WriteTwinYaml(const std::string& path,
                   const Dataset& real,
                   const TwinIdentification& id,
                   const TwinProvenance& provenance,
                   const TwinFidelity* fidelity,
                   const TwinFidelity* before = nullptr,
                   const TwinCalibration* calibration = nullptr,
                   const sim::TwinModel* identified = nullptr,
                   const GnssTrack* track = nullptr,
                   const std::vector<StatisticComparison>* gnss_statistics = nullptr,
                   const std::vector<StatisticComparison>* gnss_statistics_before = nullptr);

/// The `model:` section of a twin.yaml. Throws InputError naming the file, line and key on a
/// missing section, an unknown or missing key, or a value that is not a finite number >= 0.
sim::TwinModel ReadTwinModel(const std::string& path);

/// A twin.yaml's document (yaml-cpp; the caller includes <yaml-cpp/yaml.h>). Throws InputError
/// naming `path` for a file that cannot be opened ("cannot open the file") or is not YAML (the
/// parser's line and message). ReadTwinModel and `skerry report` read through it.
YAML::Node LoadTwinYamlDocument(const std::string& path);

}  // namespace skerry
