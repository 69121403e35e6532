// Fuzz target for the point-cloud readers (geo/point_cloud.h, LoadPointCloud): the first byte
// picks the file's extension, the rest are the file. .las is skerry's own LAS 1.0-1.4 reader
// (header, VLRs and extended VLRs, point formats 0-10, the CRS from WKT or GeoTIFF keys) and
// .bin its KITTI reader: binary formats parsed by hand, where a count or an offset read from the
// file decides what is read next. .pcd and .ply go through PCL (the module skerry loads).

#include "fuzz_files.h"
#include "skerry/core/input_error.h"
#include "skerry/geo/point_cloud.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  if (size == 0) return 0;
  static const char* const kExtension[] = {".las", ".bin", ".pcd", ".ply"};
  const std::string path = Scratch() + "/cloud" + kExtension[data[0] % 4];
  Write(path, Bytes(data + 1, size - 1));
  try {
    const skerry::geo::PointCloud cloud = skerry::geo::LoadPointCloud(path);
    // What a reader accepted is whole: one attribute per point where there are any.
    const size_t n = cloud.points.size();
    if ((!cloud.intensity.empty() && cloud.intensity.size() != n) ||
        (!cloud.classification.empty() && cloud.classification.size() != n) ||
        (!cloud.return_number.empty() && cloud.return_number.size() != n) ||
        (!cloud.time_s.empty() && cloud.time_s.size() != n)) {
      std::abort();
    }
  } catch (const skerry::InputError& e) {
    Rejected(e);
  }
  return 0;
}
