// Fuzz target for the estimator configuration reader (LoadEstimatorConfig).

#include "fuzz_files.h"
#include "skerry/core/input_error.h"
#include "skerry/solvers/estimator_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  const std::string path = Scratch() + "/config.yaml";
  Write(path, Bytes(data, size));
  try {
    skerry::LoadEstimatorConfig(path);
  } catch (const skerry::InputError& e) {
    Rejected(e);
  }
  return 0;
}
