// Fuzz target for the twin model reader (ReadTwinModel: skerry twin --model).

#include "fuzz_files.h"
#include "skerry/core/input_error.h"
#include "skerry/twin/twin_yaml.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  const std::string path = Scratch() + "/twin.yaml";
  Write(path, Bytes(data, size));
  try {
    skerry::ReadTwinModel(path);
  } catch (const skerry::InputError& e) {
    Rejected(e);
  }
  return 0;
}
