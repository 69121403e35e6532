// Fuzz target for LoadDataset: the bytes become one file of a small valid dataset, chosen at
// build time (SKERRY_FUZZ_FILE: dataset.yaml, imu.csv, gnss.csv, pose_fixes.csv,
// groundtruth.tum, lidar.csv, or one of the simulator's optional files events.csv,
// truth_states.csv, pose_fix_outliers.csv); the others stay valid, so the fuzzer reaches each
// file's own reader.

#include <cstdlib>

#include "fuzz_files.h"
#include "skerry/core/input_error.h"
#include "skerry/io/dataset.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  const std::string dir = Scratch();
  const std::vector<std::pair<std::string, std::string>> files = {
      {"dataset.yaml", kDatasetYaml},
      {"imu.csv", kImuCsv},
      {"gnss.csv", kGnssCsv},
      {"pose_fixes.csv", kPoseFixesCsv},
      {"groundtruth.tum", kGroundTruthTum},
      {"lidar.csv", kLidarCsv}};
  for (const auto& [name, text] : files) {
    Write(dir + "/" + name, name == SKERRY_FUZZ_FILE ? Bytes(data, size) : text);
  }
  Write(dir + "/scans/a.pcd", "");
  Write(dir + "/scans/b.pcd", "");
  // The optional files are read when present: only the fuzzed one is.
  for (const char* name : {"events.csv", "truth_states.csv", "pose_fix_outliers.csv"}) {
    if (std::string(name) == SKERRY_FUZZ_FILE) Write(dir + "/" + name, Bytes(data, size));
  }
  try {
    skerry::LoadDataset(dir);
  } catch (const skerry::InputError& e) {
    Rejected(e);
  }
  return 0;
}
