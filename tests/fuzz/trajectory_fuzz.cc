// Fuzz target for the trajectory readers `evaluate` and `export` use: the first byte picks TUM,
// KITTI (with its .times sidecar from the part after a "====" line, when there is one) or EuRoC
// CSV; the rest is the file.

#include "fuzz_files.h"
#include "skerry/core/input_error.h"
#include "skerry/io/trajectory_formats.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  if (size == 0) return 0;
  const std::string dir = Scratch();
  const int pick = data[0] % 3;
  const auto [file, times] = SplitTwo(Bytes(data + 1, size - 1));
  const skerry::TrajectoryFormat format = pick == 0   ? skerry::TrajectoryFormat::kTum
                                          : pick == 1 ? skerry::TrajectoryFormat::kKitti
                                                      : skerry::TrajectoryFormat::kEuroc;
  const std::string path = dir + (pick == 0 ? "/t.tum" : pick == 1 ? "/t.kitti" : "/t.csv");
  Write(path, file);
  if (pick == 1 && !times.empty()) Write(skerry::KittiTimesPath(path), times);
  try {
    skerry::ReadTrajectory(path, format);
  } catch (const skerry::InputError& e) {
    Rejected(e);
  }
  return 0;
}
