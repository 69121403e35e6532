#include "skerry/geo/las_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "las_crs.h"
#include "skerry/core/input_error.h"

namespace skerry::geo {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the LAS reader copies little-endian fields straight into host integers");

// Bytes of each point data record format 0..10 (LAS 1.4 R15, tables 7-17).
constexpr int kFormatSize[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
// Public header block sizes by minor version.
constexpr int kHeaderSize12 = 227;
constexpr int kHeaderSize13 = 235;
constexpr int kHeaderSize14 = 375;
constexpr int kVlrHeaderSize = 54;
constexpr int kEvlrHeaderSize = 60;

template <typename T>
T Get(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

std::string FixedString(const std::uint8_t* p, size_t n) {
  size_t len = 0;
  while (len < n && p[len] != 0) ++len;
  return std::string(reinterpret_cast<const char*>(p), len);
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

class File {
 public:
  explicit File(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    std::error_code ec;
    if (!in_ || !std::filesystem::is_regular_file(path, ec)) {
      throw InputError(path, 0, "", "cannot open the file");
    }
    size_ = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(path, 0, "", "cannot read its size: " + ec.message());
  }
  std::uint64_t size() const { return size_; }

  // Reads n bytes at offset; InputError (field) if the file ends first.
  std::vector<std::uint8_t> Read(std::uint64_t offset, std::uint64_t n, const std::string& field) {
    if (offset > size_ || n > size_ - offset) {
      throw InputError(path_, 0, field,
                       "the file ends at byte " + std::to_string(size_) + " before " +
                           std::to_string(offset + n) + " (truncated?)");
    }
    std::vector<std::uint8_t> out(n);
    in_.seekg(static_cast<std::streamoff>(offset));
    in_.read(reinterpret_cast<char*>(out.data()), static_cast<std::streamsize>(n));
    if (!in_) throw InputError(path_, 0, field, "read error");
    return out;
  }

 private:
  std::string path_;
  std::ifstream in_;
  std::uint64_t size_ = 0;
};

void ParseHeader(File& file, const std::string& path, LasFile& out) {
  if (Lower(std::filesystem::path(path).extension().string()) == ".laz") {
    throw InputError(path, 0, "point_format",
                     "compressed LAS (LAZ) is not supported: decompress it to .las first");
  }
  const std::vector<std::uint8_t> fixed = file.Read(0, kHeaderSize12, "header");
  const std::uint8_t* b = fixed.data();
  if (std::memcmp(b, "LASF", 4) != 0) {
    throw InputError(path, 0, "signature", "not a LAS file (no 'LASF' signature)");
  }
  LasHeader& h = out.header;
  h.global_encoding = Get<std::uint16_t>(b + 6);
  h.version_major = b[24];
  h.version_minor = b[25];
  if (h.version_major != 1 || h.version_minor > 4) {
    throw InputError(path, 0, "version",
                     "LAS " + std::to_string(h.version_major) + "." +
                         std::to_string(h.version_minor) + " is not supported (1.0-1.4)");
  }
  h.header_size = Get<std::uint16_t>(b + 94);
  const int needed = h.version_minor >= 4   ? kHeaderSize14
                     : h.version_minor == 3 ? kHeaderSize13
                                            : kHeaderSize12;
  if (h.header_size < needed) {
    throw InputError(path, 0, "header_size",
                     "LAS 1." + std::to_string(h.version_minor) + " needs a header of at least " +
                         std::to_string(needed) + " bytes, the file says " +
                         std::to_string(h.header_size));
  }
  h.offset_to_points = Get<std::uint32_t>(b + 96);
  h.vlr_count = Get<std::uint32_t>(b + 100);
  const std::uint8_t format_byte = b[104];
  h.record_length = Get<std::uint16_t>(b + 105);
  h.legacy_point_count = Get<std::uint32_t>(b + 107);
  for (int k = 0; k < 3; ++k) {
    h.scale[k] = Get<double>(b + 131 + 8 * k);
    h.offset[k] = Get<double>(b + 155 + 8 * k);
    h.max[k] = Get<double>(b + 179 + 16 * k);
    h.min[k] = Get<double>(b + 187 + 16 * k);
  }
  // LASzip marks compressed point formats by setting bit 7 (and some writers bit 6).
  if (format_byte & 0xC0) {
    throw InputError(path, 0, "point_format",
                     "compressed LAS (LAZ) is not supported: decompress it to .las first");
  }
  h.point_format = format_byte;
  if (h.point_format > 10) {
    throw InputError(path, 0, "point_format",
                     "point data format " + std::to_string(h.point_format) + " is not 0-10");
  }
  if (h.point_format >= 6 && h.version_minor < 4) {
    throw InputError(path, 0, "point_format",
                     "point data format " + std::to_string(h.point_format) + " needs LAS 1.4");
  }
  if (h.record_length < kFormatSize[h.point_format]) {
    throw InputError(path, 0, "point_format",
                     "record length " + std::to_string(h.record_length) +
                         " is shorter than format " + std::to_string(h.point_format) + "'s " +
                         std::to_string(kFormatSize[h.point_format]) + " bytes");
  }
  for (int k = 0; k < 3; ++k) {
    if (!(h.scale[k] > 0.0) || !std::isfinite(h.scale[k]) || !std::isfinite(h.offset[k])) {
      throw InputError(path, 0, "scale", "scale factors must be finite and > 0");
    }
  }
  h.point_count = h.legacy_point_count;
  if (h.version_minor >= 3) {
    const std::vector<std::uint8_t> ext = file.Read(0, h.header_size, "header");
    h.waveform_start = Get<std::uint64_t>(ext.data() + 227);
    if (h.version_minor >= 4) {
      h.evlr_start = Get<std::uint64_t>(ext.data() + 235);
      h.evlr_count = Get<std::uint32_t>(ext.data() + 243);
      h.extended_point_count = Get<std::uint64_t>(ext.data() + 247);
      if (h.extended_point_count != 0) {
        if (h.legacy_point_count != 0 && h.legacy_point_count != h.extended_point_count) {
          throw InputError(path, 0, "point_count",
                           "legacy point count " + std::to_string(h.legacy_point_count) +
                               " and extended point count " +
                               std::to_string(h.extended_point_count) + " disagree");
        }
        h.point_count = h.extended_point_count;
      }
    }
  }
  if (h.offset_to_points < h.header_size) {
    throw InputError(path, 0, "offset_to_points",
                     "point data offset " + std::to_string(h.offset_to_points) +
                         " lies inside the header block");
  }

  // VLRs between the header and the points.
  std::uint64_t at = h.header_size;
  for (std::uint32_t i = 0; i < h.vlr_count; ++i) {
    const std::vector<std::uint8_t> vh = file.Read(at, kVlrHeaderSize, "vlr");
    LasVlr vlr;
    vlr.user_id = FixedString(vh.data() + 2, 16);
    vlr.record_id = Get<std::uint16_t>(vh.data() + 18);
    const std::uint16_t length = Get<std::uint16_t>(vh.data() + 20);
    vlr.description = FixedString(vh.data() + 22, 32);
    if (at + kVlrHeaderSize + length > h.offset_to_points) {
      throw InputError(path, 0, "vlr",
                       "VLR " + std::to_string(i) + " runs past the point data offset " +
                           std::to_string(h.offset_to_points));
    }
    vlr.data = file.Read(at + kVlrHeaderSize, length, "vlr");
    out.vlrs.push_back(std::move(vlr));
    at += kVlrHeaderSize + length;
  }

  // The point data must fill exactly the space the header gives it.
  const std::uint64_t file_size = file.size();
  const std::uint64_t available =
      file_size > h.offset_to_points ? file_size - h.offset_to_points : 0;
  const std::uint64_t whole_records = available / h.record_length;
  const bool waveform_inside =
      h.version_minor >= 3 && (h.global_encoding & 0x2) && h.waveform_start > 0;
  std::uint64_t data_end_expected = file_size;
  if (h.version_minor >= 4 && h.evlr_count > 0) {
    data_end_expected = h.evlr_start;
  } else if (waveform_inside) {
    data_end_expected = h.waveform_start;
  }
  const std::uint64_t capacity_records =
      data_end_expected > h.offset_to_points
          ? (data_end_expected - h.offset_to_points) / h.record_length
          : 0;
  const bool fits = h.point_count <= whole_records;
  const bool exact =
      fits && h.offset_to_points + h.point_count * h.record_length == data_end_expected;
  if (!exact) {
    const std::string count = std::to_string(h.point_count);
    const std::string record = std::to_string(h.record_length);
    if (!fits) {
      throw InputError(path, 0, "point_count",
                       "the header says " + count + " points of " + record + " bytes from byte " +
                           std::to_string(h.offset_to_points) + ", but the file has " +
                           std::to_string(file_size) + " bytes, room for " +
                           std::to_string(whole_records) +
                           " points: the file is truncated or the point count is wrong");
    }
    throw InputError(path, 0, "point_count",
                     "the header says " + count + " points but the point data section holds " +
                         std::to_string(capacity_records) + " records of " + record + " bytes (" +
                         std::to_string(data_end_expected - h.offset_to_points) +
                         " bytes): the point count is wrong");
  }

  // 1.4 extended VLRs after the points.
  if (h.version_minor >= 4) {
    at = h.evlr_start;
    for (std::uint32_t i = 0; i < h.evlr_count; ++i) {
      const std::vector<std::uint8_t> vh = file.Read(at, kEvlrHeaderSize, "evlr");
      LasVlr vlr;
      vlr.extended = true;
      vlr.user_id = FixedString(vh.data() + 2, 16);
      vlr.record_id = Get<std::uint16_t>(vh.data() + 18);
      const std::uint64_t length = Get<std::uint64_t>(vh.data() + 20);
      vlr.description = FixedString(vh.data() + 28, 32);
      vlr.data = file.Read(at + kEvlrHeaderSize, length, "evlr");
      out.vlrs.push_back(std::move(vlr));
      at += kEvlrHeaderSize + length;
    }
  }

  const internal::DecodedCrs crs = internal::DecodeLasCrs(out.vlrs);
  out.cloud.path = path;
  out.cloud.frame = CloudFrame::kCrs;
  out.cloud.crs_wkt = crs.wkt;
  out.cloud.crs_note = crs.note;
}

}  // namespace

LasFile ReadLasHeader(const std::string& path) {
  File file(path);
  LasFile out;
  ParseHeader(file, path, out);
  return out;
}

LasFile ReadLas(const std::string& path) {
  File file(path);
  LasFile out;
  ParseHeader(file, path, out);
  const LasHeader& h = out.header;
  PointCloud& cloud = out.cloud;
  const size_t n = static_cast<size_t>(h.point_count);
  cloud.points.resize(n);
  cloud.intensity.resize(n);
  cloud.classification.resize(n);
  cloud.return_number.resize(n);
  const bool extended_format = h.point_format >= 6;

  constexpr size_t kChunk = 65536;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (size_t first = 0; first < n; first += kChunk) {
    const size_t count = std::min(kChunk, n - first);
    const std::vector<std::uint8_t> chunk =
        file.Read(h.offset_to_points + static_cast<std::uint64_t>(first) * h.record_length,
                  static_cast<std::uint64_t>(count) * h.record_length, "points");
    for (size_t k = 0; k < count; ++k) {
      const std::uint8_t* r = chunk.data() + k * h.record_length;
      Eigen::Vector3d& p = cloud.points[first + k];
      for (int a = 0; a < 3; ++a) {
        p[a] = Get<std::int32_t>(r + 4 * a) * h.scale[a] + h.offset[a];
      }
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
      cloud.intensity[first + k] = Get<std::uint16_t>(r + 12);
      if (extended_format) {
        cloud.return_number[first + k] = r[14] & 0x0F;
        cloud.classification[first + k] = r[16];
      } else {
        cloud.return_number[first + k] = r[14] & 0x07;
        cloud.classification[first + k] = r[15] & 0x1F;
      }
    }
  }
  if (n > 0) {
    out.read_min = lo;
    out.read_max = hi;
    const char* axis = "xyz";
    for (int a = 0; a < 3; ++a) {
      // One scale step of slack (writers round the header bounds), plus rounding of the doubles.
      const double slack = h.scale[a] * (1.0 + 1e-6);
      if (lo[a] < h.min[a] - slack || hi[a] > h.max[a] + slack) {
        throw InputError(path, 0, "bounds",
                         std::string("points span ") + axis[a] + " " + std::to_string(lo[a]) +
                             " .. " + std::to_string(hi[a]) + " but the header says " +
                             std::to_string(h.min[a]) + " .. " + std::to_string(h.max[a]));
      }
    }
  }
  return out;
}

}  // namespace skerry::geo
