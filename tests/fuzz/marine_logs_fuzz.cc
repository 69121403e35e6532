// Fuzz target for the marine log readers: the first byte picks NMEA 0183 (nmea0183::ReadLog) or
// NMEA 2000 as canboat JSON (nmea2000::ReadCanboatJson); the rest is the log. What was read is
// then made into a dataset (MarineLogToDataset), as `skerry import` does.

#include "fuzz_files.h"
#include "skerry/core/input_error.h"
#include "skerry/io/marine_dataset.h"
#include "skerry/io/nmea0183.h"
#include "skerry/io/nmea2000_json.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  if (size == 0) return 0;
  const std::string path = Scratch() + "/log";
  Write(path, Bytes(data + 1, size - 1));
  try {
    const skerry::MarineLog log = data[0] % 2 == 0 ? skerry::nmea0183::ReadLog(path)
                                                   : skerry::nmea2000::ReadCanboatJson(path);
    skerry::MarineLogToDataset(log);
  } catch (const skerry::InputError& e) {
    Rejected(e);
  }
  return 0;
}
