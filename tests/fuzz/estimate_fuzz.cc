// Fuzz target for a run folder's estimate as `evaluate`, `fidelity`, `compare --collect` and
// `report` read it: states.csv, then after a "====" line covariances.csv.

#include "fuzz_files.h"
#include "skerry/core/input_error.h"
#include "skerry/io/estimate_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  const std::string dir = Scratch();
  const auto [states, covariances] = SplitTwo(Bytes(data, size));
  Write(dir + "/states.csv", states);
  if (!covariances.empty()) Write(dir + "/covariances.csv", covariances);
  try {
    skerry::ReadEstimate(dir + "/states.csv", dir + "/covariances.csv");
  } catch (const skerry::InputError& e) {
    Rejected(e);
  }
  return 0;
}
