// Fuzz target for the JSON a run or compare folder holds, as `report` and `compare --collect`
// read it: the first byte picks summary.json of a run folder (report), plan.json of a compare
// folder (collect), or table.json (report of a comparison); the rest is the file.

#include "comparison.h"
#include "fuzz_files.h"
#include "report_page.h"
#include "skerry/core/input_error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  if (size == 0) return 0;
  const std::string dir = Scratch();
  const std::string text = Bytes(data + 1, size - 1);
  try {
    switch (data[0] % 3) {
      case 0:
        Write(dir + "/summary.json", text);
        Write(dir + "/states.csv",
              "t,px,py,pz,qx,qy,qz,qw,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz,sigma_px,sigma_py,sigma_pz,"
              "sigma_heading_deg\n"
              "1.0,0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0,,,,\n");
        skerry::cli::ReportData({dir}, 100);
        break;
      case 1:
        Write(dir + "/plan.json", text);
        skerry::cli::Collect(dir);
        break;
      default:
        Write(dir + "/table.json", text);
        Write(dir + "/plan.json",
              "{\"format\": \"skerry-compare-plan/1\", \"seeds\": [1], \"datasets\": [], "
              "\"configs\": [{\"name\": \"a\", \"file\": \"configs/a.yaml\"}], \"jobs\": []}");
        skerry::cli::ReportData({dir}, 100);
        break;
    }
  } catch (const skerry::InputError& e) {
    Rejected(e);
  }
  return 0;
}
