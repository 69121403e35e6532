#include "kitti_bin.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "skerry/core/input_error.h"

namespace skerry::geo::internal {

PointCloud ReadKittiBin(const std::string& path) {
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "KITTI .bin is little-endian");
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path, 0, "", "cannot read the file: " + ec.message());
  constexpr size_t kRecord = 4 * sizeof(float);
  if (size % kRecord != 0) {
    throw InputError(path, 0, "",
                     "a KITTI .bin holds 16-byte records (float32 x, y, z, reflectance), but the "
                     "file has " +
                         std::to_string(size) + " bytes");
  }
  const size_t n = size / kRecord;
  std::vector<float> raw(4 * n);
  std::ifstream in(path, std::ios::binary);
  in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(size));
  if (!in) throw InputError(path, 0, "", "read error");
  PointCloud cloud;
  cloud.path = path;
  cloud.frame = CloudFrame::kSensor;
  cloud.points.resize(n);
  cloud.intensity.resize(n);
  for (size_t i = 0; i < n; ++i) {
    cloud.points[i] = Eigen::Vector3d(raw[4 * i], raw[4 * i + 1], raw[4 * i + 2]);
    cloud.intensity[i] = raw[4 * i + 3];
  }
  return cloud;
}

}  // namespace skerry::geo::internal
