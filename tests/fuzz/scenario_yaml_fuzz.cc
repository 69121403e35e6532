// Fuzz target for the simulator's scenario reader (sim::LoadScenario).

#include "fuzz_files.h"
#include "skerry/core/input_error.h"
#include "skerry/sim/scenario.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  const std::string path = Scratch() + "/scenario.yaml";
  Write(path, Bytes(data, size));
  try {
    skerry::sim::LoadScenario(path);
  } catch (const skerry::InputError& e) {
    Rejected(e);
  }
  return 0;
}
