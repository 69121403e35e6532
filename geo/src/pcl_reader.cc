#include "pcl_reader.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <vector>

#include "skerry/core/input_error.h"

namespace skerry::geo::internal {
namespace {

bool HasField(const pcl::PCLPointCloud2& blob, const std::string& name) {
  return std::any_of(blob.fields.begin(), blob.fields.end(),
                     [&](const pcl::PCLPointField& f) { return f.name == name; });
}

// The per-point time field `t` as seconds: FLOAT32 / FLOAT64 are seconds after the scan's stamp
// (skerry's simulator, most drivers' deskew fields); an integer field is nanoseconds (the
// Ouster driver's uint32 `t`). Empty when the cloud has no `t`.
std::vector<float> ReadTimes(const pcl::PCLPointCloud2& blob, const std::string& path) {
  const auto field = std::find_if(blob.fields.begin(), blob.fields.end(),
                                  [](const pcl::PCLPointField& f) { return f.name == "t"; });
  if (field == blob.fields.end()) return {};
  using F = pcl::PCLPointField;
  std::uint32_t size = 0;
  switch (field->datatype) {
    case F::FLOAT32:
    case F::UINT32:
    case F::INT32:
      size = 4;
      break;
    case F::FLOAT64:
    case F::UINT64:
    case F::INT64:
      size = 8;
      break;
    default:
      throw InputError(path, 0, "t",
                       "the time field must be a float (seconds) or a 32/64-bit integer "
                       "(nanoseconds)");
  }
  if (field->count != 1 || field->offset + size > blob.point_step) {
    throw InputError(path, 0, "t", "the time field must be one number per point");
  }
  if (blob.height > 0 && blob.width > 0 &&
      blob.data.size() < static_cast<size_t>(blob.height - 1) * blob.row_step +
                             static_cast<size_t>(blob.width) * blob.point_step) {
    throw InputError(path, 0, "t", "the cloud's data is shorter than its header says");
  }
  const bool seconds = field->datatype == F::FLOAT32 || field->datatype == F::FLOAT64;
  std::vector<float> times;
  times.reserve(static_cast<size_t>(blob.width) * blob.height);
  for (std::uint32_t row = 0; row < blob.height; ++row) {
    for (std::uint32_t col = 0; col < blob.width; ++col) {
      const std::uint8_t* p = blob.data.data() + static_cast<size_t>(row) * blob.row_step +
                              col * blob.point_step + field->offset;
      double v = 0.0;
      switch (field->datatype) {
        case F::FLOAT32: {
          float f;
          std::memcpy(&f, p, sizeof(f));
          v = f;
          break;
        }
        case F::FLOAT64:
          std::memcpy(&v, p, sizeof(v));
          break;
        case F::UINT32: {
          std::uint32_t u;
          std::memcpy(&u, p, sizeof(u));
          v = u;
          break;
        }
        case F::INT32: {
          std::int32_t u;
          std::memcpy(&u, p, sizeof(u));
          v = u;
          break;
        }
        case F::UINT64: {
          std::uint64_t u;
          std::memcpy(&u, p, sizeof(u));
          v = static_cast<double>(u);
          break;
        }
        case F::INT64: {
          std::int64_t u;
          std::memcpy(&u, p, sizeof(u));
          v = static_cast<double>(u);
          break;
        }
        default:
          break;
      }
      times.push_back(static_cast<float>(seconds ? v : v * 1e-9));
    }
  }
  return times;
}

// Bytes of one value of a PCL field type; 0 for a type PCL does not define.
std::uint64_t TypeSize(std::uint8_t datatype) {
  using F = pcl::PCLPointField;
  switch (datatype) {
    case F::INT8:
    case F::UINT8:
      return 1;
    case F::INT16:
    case F::UINT16:
      return 2;
    case F::INT32:
    case F::UINT32:
    case F::FLOAT32:
      return 4;
    case F::FLOAT64:
    case F::INT64:
    case F::UINT64:
      return 8;
    default:
      return 0;
  }
}

// Every field of a point record inside it: its type's size times its count from its offset
// fits the record. PCL's own readers and conversions trust that.
// `when`, if not empty, is said after the message.
void RequireFieldsInsideTheRecord(const pcl::PCLPointCloud2& blob,
                                  const std::string& path,
                                  const std::string& when = "") {
  for (const pcl::PCLPointField& f : blob.fields) {
    const std::uint64_t size = TypeSize(f.datatype);
    if (size == 0 || f.count == 0 ||
        static_cast<std::uint64_t>(f.offset) + size * f.count > blob.point_step) {
      throw InputError(path, 0, f.name,
                       "the field's type, count or offset does not fit the " +
                           std::to_string(blob.point_step) + "-byte point record" +
                           (when.empty() ? "" : " (" + when + ")"));
    }
  }
}

// The layout the reader parsed is one PCL's conversion can copy from: every field inside a
// point, every point inside the data. PCL's fromPCLPointCloud2 trusts both, and a malformed
// header (a SIZE line garbled, COUNTs that overrun the record) made it read past the data.
void RequireConsistentLayout(const pcl::PCLPointCloud2& blob, const std::string& path) {
  RequireFieldsInsideTheRecord(blob, path);
  const std::uint64_t width = blob.width, height = blob.height;
  if (width * height == 0) return;
  const bool rows_fit = blob.row_step >= width * blob.point_step;
  const std::uint64_t needed =
      (height - 1) * static_cast<std::uint64_t>(blob.row_step) + width * blob.point_step;
  if (!rows_fit || blob.data.size() < needed) {
    throw InputError(path, 0, "",
                     "the header announces " + std::to_string(width * height) + " points of " +
                         std::to_string(blob.point_step) + " bytes but the data holds " +
                         std::to_string(blob.data.size()) + " bytes");
  }
}

PointCloud FromBlob(const pcl::PCLPointCloud2& blob, const std::string& path) {
  for (const char* axis : {"x", "y", "z"}) {
    if (!HasField(blob, axis)) {
      throw InputError(path, 0, axis, std::string("the cloud has no '") + axis + "' field");
    }
  }
  RequireConsistentLayout(blob, path);
  PointCloud cloud;
  cloud.path = path;
  cloud.frame = CloudFrame::kSensor;
  // An empty cloud (a scan that saw nothing) is valid; PCL's conversion indexes its first point.
  if (static_cast<size_t>(blob.width) * blob.height == 0) return cloud;
  if (HasField(blob, "intensity")) {
    pcl::PointCloud<pcl::PointXYZI> points;
    pcl::fromPCLPointCloud2(blob, points);
    cloud.points.reserve(points.size());
    cloud.intensity.reserve(points.size());
    for (const pcl::PointXYZI& p : points) {
      cloud.points.emplace_back(p.x, p.y, p.z);
      cloud.intensity.push_back(p.intensity);
    }
  } else {
    pcl::PointCloud<pcl::PointXYZ> points;
    pcl::fromPCLPointCloud2(blob, points);
    cloud.points.reserve(points.size());
    for (const pcl::PointXYZ& p : points) cloud.points.emplace_back(p.x, p.y, p.z);
  }
  cloud.time_s = ReadTimes(blob, path);
  return cloud;
}

// The size of a file that must exist.
std::uint64_t RequireFileSize(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(path, 0, "", "no such file");
  }
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path, 0, "", "cannot read its size: " + ec.message());
  return size;
}

// A count in a PCD header: digits only (an unsigned read would take "-5" as 2^64 - 5).
std::optional<std::uint64_t> Count(const std::string& word) {
  if (word.empty() || word.size() > 15 ||
      !std::all_of(word.begin(), word.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return std::nullopt;
  }
  return std::stoull(word);
}

// PCL's readHeader sizes the whole cloud (WIDTH x HEIGHT records) before it reads a byte of it:
// a 200-byte file that announced 10^9 points had it ask for 13 GB. The header's announcement is
// checked against the bytes after it first: at least one character per value (ascii, or no
// DATA line), the records themselves (binary), or a 1024th of them (binary_compressed: LZF's
// best ratio is about 90).
// PCL also reserves one token per value of a point before it reads a line, even for an empty
// cloud (COUNT 4294967293 had it ask for 137 GB), and a record's bytes follow SIZE: a field is
// 1, 2, 4 or 8 bytes (PCL's types) and a point holds at most kMaxPcdValuesPerPoint values (the
// largest PCL descriptors hold under 2000).
// A header without SIZE counts a byte a value (FIELDS, or one per point without them).
constexpr std::uint64_t kMaxPcdValuesPerPoint = 1 << 16;
// The keys PCL's PCD header parser knows, each taken by a line's first letters.
constexpr const char* kPcdHeaderKeys[] = {"VERSION",   "FIELDS", "COLUMNS", "SIZE",
                                          "TYPE",      "COUNT",  "WIDTH",   "HEIGHT",
                                          "VIEWPOINT", "POINTS", "DATA"};

void RequirePcdFitsItsFile(const std::string& path, std::uint64_t file_size) {
  std::ifstream in(path, std::ios::binary);
  std::vector<std::uint64_t> sizes, counts;
  int count_line = 0;
  std::uint64_t width = 0, height = 1, points = 0, header_bytes = 0, fields = 0;
  std::string line, data;
  // Up to DATA, however many comment lines come first: PCL reads the header to there.
  for (int n = 1; std::getline(in, line); ++n) {
    header_bytes += line.size() + 1;
    std::istringstream words(line);
    std::string token, word;
    words >> token;
    // PCL takes a line by its key's first letters ("SIZET 1 1" is a SIZE line, "COUNTI" COUNT).
    std::string key;
    for (const char* k : kPcdHeaderKeys) {
      if (token.rfind(k, 0) == 0) key = k;
    }
    // PCL reads these leniently ("1-1" as 1, "-2" as a huge count): here they are counts or
    // the file is refused.
    const auto count = [&]() {
      const auto c = Count(word);
      if (!c) throw InputError(path, n, key, "'" + word + "' is not a count");
      return *c;
    };
    if (key == "FIELDS" || key == "COLUMNS") {
      fields = 0;
      while (words >> word) ++fields;
    }
    if (key == "SIZE") {
      while (words >> word) {
        sizes.push_back(count());
        const std::uint64_t s = sizes.back();
        if (s != 1 && s != 2 && s != 4 && s != 8) {
          throw InputError(path, n, key,
                           "a field of " + word + " bytes (PCD fields are 1, 2, 4 or 8)");
        }
      }
    }
    if (key == "COUNT") {
      count_line = n;
      while (words >> word) counts.push_back(count());
    }
    // A repeated line: PCL sizes the cloud at each one (a POINTS of 99999999993 followed by a
    // POINTS 3 had it ask for 3.6 TB at the first), so the largest counts.
    if ((key == "WIDTH" || key == "HEIGHT" || key == "POINTS") && (words >> word)) {
      std::uint64_t& v = key == "WIDTH" ? width : key == "HEIGHT" ? height : points;
      v = std::max(v, count());
    }
    if (key == "DATA") {
      words >> data;
      // PCL reads on past DATA for as long as lines look like header lines (a later POINTS or
      // FIELDS line counts: a POINTS of 99999999993 after DATA asked for 3.6 TB, a FIELDS line
      // after it had PCL's ascii reader crash). The header ends at DATA here.
      std::string next;
      for (int m = n + 1; std::getline(in, next); ++m) {
        std::istringstream next_words(next);
        std::string first;
        if (!(next_words >> first) || first[0] == '#') continue;  // PCL skips these too
        for (const char* k : kPcdHeaderKeys) {
          if (first.rfind(k, 0) == 0) {
            throw InputError(path, m, k,
                             "a header line after DATA (line " + std::to_string(n) +
                                 "), where a PCD header ends");
          }
        }
        break;
      }
      break;
    }
  }
  if (!counts.empty() && counts.size() != sizes.size()) {
    throw InputError(path, 0, "COUNT",
                     std::to_string(counts.size()) + " counts for " + std::to_string(sizes.size()) +
                         " field sizes");
  }
  std::uint64_t per_point = 0;
  // Saturating: a long COUNT line of 15-digit counts could overflow 64 bits.
  for (const std::uint64_t c : counts) {
    per_point = std::min(per_point + c, kMaxPcdValuesPerPoint + 1);
  }
  if (per_point > kMaxPcdValuesPerPoint) {
    throw InputError(path, count_line, "COUNT",
                     "a point of more than " + std::to_string(kMaxPcdValuesPerPoint) +
                         " values: not a point cloud PCL can read");
  }
  // Without a SIZE line PCL still sizes the cloud by POINTS (a 150-byte file with POINTS
  // 99999999993 asked for 3.6 TB): every value takes at least a byte.
  if (sizes.empty()) sizes.assign(std::max<std::uint64_t>(fields, 1), 1);
  if (counts.empty()) counts.assign(sizes.size(), 1);
  // In doubles: a plausibility bound, where a product of counts could overflow 64 bits.
  double record = 0.0, values = 0.0;
  for (size_t i = 0; i < sizes.size(); ++i) {
    record += static_cast<double>(sizes[i]) * static_cast<double>(counts[i]);
    values += static_cast<double>(counts[i]);
  }
  const double announced = std::max(static_cast<double>(points),
                                    static_cast<double>(width) * static_cast<double>(height));
  const std::uint64_t body = file_size > header_bytes ? file_size - header_bytes : 0;
  // Without a DATA line that PCL knows, as ascii: PCL sizes the cloud all the same.
  double needed = announced * values;
  if (data == "binary") needed = announced * record;
  if (data == "binary_compressed") needed = announced * record / 1024.0;
  if (needed > static_cast<double>(body)) {
    char bytes[32];
    std::snprintf(bytes, sizeof(bytes), "%.0f", record);
    throw InputError(path, 0, "",
                     "the PCD header announces " + std::to_string(std::max(points, width)) +
                         (height > 1 ? " x " + std::to_string(height) : std::string()) +
                         " points of " + bytes + " bytes (" +
                         (data.empty() ? std::string("no DATA line") : data) +
                         ") but the file has " + std::to_string(body) +
                         " bytes after its header: truncated or a wrong count");
  }
}

PointCloud ReadPcdFile(const std::string& path) {
  const std::uint64_t size = RequireFileSize(path);
  RequirePcdFitsItsFile(path, size);
  pcl::PCDReader reader;
  // PCL 1.13's read() crashes on some malformed files (a header without FIELDS): check the
  // header first, and that a binary body holds every point it announces.
  {
    pcl::PCLPointCloud2 header;
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int version = 0;
    int data_type = 0;
    unsigned int data_index = 0;
    if (reader.readHeader(path, header, origin, orientation, version, data_type, data_index) < 0 ||
        header.fields.empty() || header.point_step == 0) {
      throw InputError(path, 0, "", "PCL cannot read it as a PCD file (no valid header)");
    }
    for (const char* axis : {"x", "y", "z"}) {
      if (!HasField(header, axis)) {
        throw InputError(path, 0, axis, std::string("the cloud has no '") + axis + "' field");
      }
    }
    // Before PCL reads the body: its ascii reader writes each value by the field's type, and
    // a garbled SIZE line (fields of 1 byte, typed as 4-byte floats) had it write past the
    // cloud's buffer, in its uninstrumented code (valgrind; under ASan it overwrote the
    // allocator's own records and surfaced thousands of inputs later).
    RequireFieldsInsideTheRecord(header, path, "its header's, before PCL reads the body");
    const std::uint64_t points = static_cast<std::uint64_t>(header.width) * header.height;
    // points * point_step can overflow for a malformed header: compare by division.
    const bool fits =
        data_index <= size && (points == 0 || (size - data_index) / points >= header.point_step);
    const std::uint64_t needed =
        fits ? data_index + points * header.point_step : std::numeric_limits<std::uint64_t>::max();
    if (data_type == 1 && !fits) {
      throw InputError(path, 0, "",
                       "the PCD header announces " + std::to_string(points) + " points (" +
                           std::to_string(needed) + " bytes) but the file has " +
                           std::to_string(size) + " bytes: truncated");
    }
    // A compressed body opens with its compressed and uncompressed sizes. PCL sizes the cloud
    // by the second (a 131-byte file saying 2^31 - 1 had it ask for 2 GB) and, where it is
    // smaller than the header's points, copies them past its end. Both must be what the header
    // says.
    if (data_type == 2) {
      std::uint32_t sizes[2] = {0, 0};
      std::ifstream body(path, std::ios::binary);
      body.seekg(static_cast<std::streamoff>(data_index));
      if (data_index > size || size - data_index < 8 ||
          !body.read(reinterpret_cast<char*>(sizes), sizeof(sizes))) {
        throw InputError(path, 0, "DATA",
                         "a binary_compressed body without its two sizes: truncated");
      }
      // sizes[1] == points * point_step, by division (the product can overflow).
      if (sizes[1] % header.point_step != 0 || sizes[1] / header.point_step != points) {
        throw InputError(path, 0, "DATA",
                         "the compressed body unpacks to " + std::to_string(sizes[1]) +
                             " bytes where the header announces " + std::to_string(points) +
                             " points of " + std::to_string(header.point_step) + " bytes");
      }
      if (sizes[0] > size - data_index - 8) {
        throw InputError(path, 0, "DATA",
                         "the compressed body says " + std::to_string(sizes[0]) +
                             " bytes but the file has " + std::to_string(size - data_index - 8) +
                             " after its sizes: truncated");
      }
    }
  }
  pcl::PCLPointCloud2 blob;
  if (reader.read(path, blob) < 0) {
    throw InputError(path, 0, "", "PCL cannot read it as a PCD file");
  }
  return FromBlob(blob, path);
}

// Bytes of one PLY property value (PLY's type names, old and new); 0 for an unknown type.
std::uint64_t PlyTypeSize(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" ||
      type == "float32") {
    return 4;
  }
  if (type == "double" || type == "float64") return 8;
  return 0;
}

// As RequirePcdFitsItsFile for PLY: PCL's reader sizes each element from its count in the header
// (a 130-byte file that announced 4e9 vertices had it ask for 48 GB). The least the elements
// need, at least one character per property (ascii) or the properties' bytes (binary; a list
// at least its count), must fit in the bytes after the header.
void RequirePlyFitsItsFile(const std::string& path, std::uint64_t file_size) {
  std::ifstream in(path, std::ios::binary);
  std::string line, format;
  std::uint64_t header_bytes = 0;
  double needed = 0.0, count = 0.0, per_element = 0.0;
  bool ended = false;
  int elements = 0;
  if (file_size == 0) throw InputError(path, 0, "ply", "not a PLY file: it is empty");
  // To end_header, however many comment lines come first.
  for (int n = 1; std::getline(in, line); ++n) {
    header_bytes += line.size() + 1;
    // A PLY file begins with the line "ply" (PCL's parser, given anything shorter, compared
    // bytes it never read: valgrind on the fuzzer's one-byte file).
    if (n == 1 && line != "ply" && line != "ply\r") {
      std::string shown;
      for (const char ch : line.substr(0, 16)) {
        shown += std::isprint(static_cast<unsigned char>(ch)) ? ch : '?';
      }
      throw InputError(path, 1, "ply",
                       "not a PLY file: it begins with '" + shown +
                           (line.size() > 16 ? "..." : "") +
                           "' where a PLY file begins with the line 'ply'");
    }
    std::istringstream words(line);
    std::string key, word;
    words >> key;
    if (key == "format") words >> format;
    if (key == "element" || key == "end_header") {
      // At least a byte an element, even of no properties: PCL steps through every element it
      // announced (2e9 vertices of a garbled property line ran past the fuzzer's 10 s).
      needed += count * std::max(per_element, 1.0);
      count = 0.0;
      per_element = 0.0;
    }
    if (key == "element") {
      ++elements;
      words >> word >> word;  // its name, then its count
      const auto c = Count(word);
      if (!c) throw InputError(path, n, "element", "'" + word + "' is not a count");
      count = static_cast<double>(*c);
    }
    if (key == "property") {
      std::string type;
      words >> type;
      if (type == "list") words >> type;  // the list's count type: its least size
      per_element += format == "ascii"
                         ? 1.0
                         : static_cast<double>(std::max<std::uint64_t>(PlyTypeSize(type), 1));
    }
    if (key == "end_header") {
      ended = true;
      break;
    }
  }
  // A header that announces elements and never ends is no PLY file, yet PCL begins each element
  // it announced (2e9 vertices took it past the fuzzer's 10 s before it found the header
  // unfinished). Anything else without end_header is left to PCL, which says what is wrong.
  if (!ended && elements > 0) {
    throw InputError(path, 0, "end_header", "the PLY header announces elements and never ends");
  }
  if (!ended) return;
  const std::uint64_t body = file_size > header_bytes ? file_size - header_bytes : 0;
  if (needed > static_cast<double>(body)) {
    char bytes[32];
    std::snprintf(bytes, sizeof(bytes), "%.0f", needed);
    throw InputError(path, 0, "element",
                     "the PLY header announces elements of at least " + std::string(bytes) +
                         " bytes (" + format + ") but the file has " + std::to_string(body) +
                         " bytes after its header: truncated or a wrong count");
  }
}

PointCloud ReadPlyFile(const std::string& path) {
  RequirePlyFitsItsFile(path, RequireFileSize(path));
  pcl::PCLPointCloud2 blob;
  pcl::PLYReader reader;
  if (reader.read(path, blob) < 0) {
    throw InputError(path, 0, "", "PCL cannot read it as a PLY file");
  }
  return FromBlob(blob, path);
}

}  // namespace
}  // namespace skerry::geo::internal

// The module's entry point (pcl_reader.h): no exception crosses the module boundary.
extern "C" __attribute__((visibility("default"))) bool skerry_pcl_read(
    const std::string& path,
    skerry::geo::internal::PclFormat format,
    skerry::geo::PointCloud* cloud,
    skerry::geo::internal::PclReadError* error) noexcept {
  using skerry::geo::internal::PclFormat;
  try {
    *cloud = format == PclFormat::kPcd ? skerry::geo::internal::ReadPcdFile(path)
                                       : skerry::geo::internal::ReadPlyFile(path);
    return true;
  } catch (const skerry::InputError& e) {
    // what() is "FILE:LINE: FIELD: message": the same error with an empty message is its prefix.
    const std::string prefix = skerry::InputError(e.file(), e.line(), e.field(), "").what();
    const std::string what = e.what();
    *error = {e.file(), e.line(), e.field(),
              what.compare(0, prefix.size(), prefix) == 0 ? what.substr(prefix.size()) : what};
  } catch (const std::exception& e) {
    *error = {path, 0, "", std::string("PCL cannot read it: ") + e.what()};
  } catch (...) {
    *error = {path, 0, "", "PCL cannot read it"};
  }
  return false;
}
