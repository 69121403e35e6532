#pragma once
// A writer of small LAS files for the tests, laid out per the LAS 1.4 R15 specification, so
// that versions, point formats and CRS records the shared data lacks can be read back.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "geo/geo_test_util.h"

namespace skerry::geo::testing {

/// A point of a synthetic LAS file, in raw (integer, unscaled) coordinates.
struct LasPoint {
  std::int32_t x = 0;
  std::int32_t y = 0;
  std::int32_t z = 0;
  std::uint16_t intensity = 0;
  std::uint8_t return_number = 1;
  std::uint8_t number_of_returns = 1;
  std::uint8_t classification = 0;
  /// Formats 0-5: the synthetic / key-point / withheld bits 5-7 of the classification byte.
  /// Formats 6-10: the classification flags and scanner channel, bits 0-5 of byte 15.
  std::uint8_t flags = 0;
};

struct LasRecord {
  std::string user_id = "LASF_Projection";
  std::uint16_t record_id = 0;
  std::vector<std::uint8_t> data;
};

/// What to write. The header's bounds are those of the points; counts are the true ones.
struct LasSpec {
  int minor = 2;
  int format = 0;
  double scale = 0.01;
  double offset_x = 0.0;
  double offset_y = 0.0;
  double offset_z = 0.0;
  std::vector<LasPoint> points;
  std::vector<LasRecord> vlrs;
  std::vector<LasRecord> evlrs;    // 1.4 only
  bool legacy_count_zero = false;  // 1.4: leave the legacy count at 0 (as for formats 6-10)
};

/// A LAS file laid out per the LAS 1.4 R15 specification (1.2 / 1.3 / 1.4 headers).
inline std::vector<std::uint8_t> MakeLas(const LasSpec& s) {
  static const int kSize[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  const int header_size = s.minor >= 4 ? 375 : s.minor == 3 ? 235 : 227;
  const int record_length = kSize[s.format];
  size_t vlr_bytes = 0;
  for (const LasRecord& v : s.vlrs) vlr_bytes += 54 + v.data.size();
  const size_t offset = header_size + vlr_bytes;
  const size_t n = s.points.size();
  std::vector<std::uint8_t> b(offset + n * record_length, 0);
  std::memcpy(b.data(), "LASF", 4);
  b[24] = 1;
  b[25] = static_cast<std::uint8_t>(s.minor);
  Poke<std::uint16_t>(b, 94, static_cast<std::uint16_t>(header_size));
  Poke<std::uint32_t>(b, 96, static_cast<std::uint32_t>(offset));
  Poke<std::uint32_t>(b, 100, static_cast<std::uint32_t>(s.vlrs.size()));
  b[104] = static_cast<std::uint8_t>(s.format);
  Poke<std::uint16_t>(b, 105, static_cast<std::uint16_t>(record_length));
  Poke<std::uint32_t>(b, 107, s.legacy_count_zero ? 0u : static_cast<std::uint32_t>(n));
  const double scale[3] = {s.scale, s.scale, s.scale};
  const double off[3] = {s.offset_x, s.offset_y, s.offset_z};
  double lo[3] = {0, 0, 0};
  double hi[3] = {0, 0, 0};
  for (size_t i = 0; i < n; ++i) {
    const std::int32_t raw[3] = {s.points[i].x, s.points[i].y, s.points[i].z};
    for (int a = 0; a < 3; ++a) {
      const double v = raw[a] * scale[a] + off[a];
      lo[a] = i == 0 ? v : std::min(lo[a], v);
      hi[a] = i == 0 ? v : std::max(hi[a], v);
    }
  }
  for (int a = 0; a < 3; ++a) {
    Poke<double>(b, 131 + 8 * a, scale[a]);
    Poke<double>(b, 155 + 8 * a, off[a]);
    Poke<double>(b, 179 + 16 * a, hi[a]);
    Poke<double>(b, 187 + 16 * a, lo[a]);
  }
  size_t at = header_size;
  for (const LasRecord& v : s.vlrs) {
    std::memcpy(b.data() + at + 2, v.user_id.data(), std::min<size_t>(16, v.user_id.size()));
    Poke<std::uint16_t>(b, at + 18, v.record_id);
    Poke<std::uint16_t>(b, at + 20, static_cast<std::uint16_t>(v.data.size()));
    std::memcpy(b.data() + at + 54, v.data.data(), v.data.size());
    at += 54 + v.data.size();
  }
  for (size_t i = 0; i < n; ++i) {
    const LasPoint& p = s.points[i];
    const size_t r = offset + i * record_length;
    Poke<std::int32_t>(b, r, p.x);
    Poke<std::int32_t>(b, r + 4, p.y);
    Poke<std::int32_t>(b, r + 8, p.z);
    Poke<std::uint16_t>(b, r + 12, p.intensity);
    if (s.format >= 6) {
      b[r + 14] =
          static_cast<std::uint8_t>((p.return_number & 0x0F) | ((p.number_of_returns & 0x0F) << 4));
      b[r + 15] = static_cast<std::uint8_t>(p.flags & 0x3F);
      b[r + 16] = p.classification;
    } else {
      b[r + 14] =
          static_cast<std::uint8_t>((p.return_number & 0x07) | ((p.number_of_returns & 0x07) << 3));
      b[r + 15] = static_cast<std::uint8_t>((p.classification & 0x1F) | (p.flags & 0xE0));
    }
  }
  if (s.minor >= 4) {
    Poke<std::uint64_t>(b, 235, s.evlrs.empty() ? 0 : b.size());
    Poke<std::uint32_t>(b, 243, static_cast<std::uint32_t>(s.evlrs.size()));
    Poke<std::uint64_t>(b, 247, n);
    for (const LasRecord& v : s.evlrs) {
      std::vector<std::uint8_t> e(60, 0);
      std::memcpy(e.data() + 2, v.user_id.data(), std::min<size_t>(16, v.user_id.size()));
      Poke<std::uint16_t>(e, 18, v.record_id);
      Poke<std::uint64_t>(e, 20, v.data.size());
      b.insert(b.end(), e.begin(), e.end());
      b.insert(b.end(), v.data.begin(), v.data.end());
    }
  }
  return b;
}

/// A GeoKeyDirectory (34735) holding only directory-stored keys: {id, value} pairs.
inline LasRecord GeoKeys(const std::vector<std::pair<int, int>>& keys) {
  std::vector<std::uint16_t> d = {1, 1, 0, static_cast<std::uint16_t>(keys.size())};
  for (const auto& [id, value] : keys) {
    d.insert(d.end(), {static_cast<std::uint16_t>(id), 0, 1, static_cast<std::uint16_t>(value)});
  }
  LasRecord r;
  r.record_id = 34735;
  r.data.resize(d.size() * 2);
  std::memcpy(r.data.data(), d.data(), r.data.size());
  return r;
}

inline LasRecord WktRecord(const std::string& wkt) {
  LasRecord r;
  r.record_id = 2112;
  r.data.assign(wkt.begin(), wkt.end());
  r.data.push_back(0);
  return r;
}

}  // namespace skerry::geo::testing
