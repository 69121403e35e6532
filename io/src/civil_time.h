#pragma once
// UTC calendar dates to days since the Unix epoch, and the date and time spellings the marine
// log readers meet. Private to skerry_io.

#include <cctype>
#include <cstdint>
#include <string_view>

#include "skerry/core/time.h"

namespace skerry {

/// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's days_from_civil).
inline std::int64_t DaysFromCivil(std::int64_t y, unsigned m, unsigned d) {
  y -= m <= 2;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

inline bool ValidDate(std::int64_t y, int m, int d) {
  static constexpr int kDays[] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (m < 1 || m > 12 || d < 1 || d > kDays[m - 1]) return false;
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  return !(m == 2 && d == 29 && !leap);
}

/// Reads `n` digits at `*pos` into `*value`, advancing `*pos`.
inline bool ReadDigits(std::string_view s, std::size_t* pos, int n, int* value) {
  if (*pos + n > s.size()) return false;
  int v = 0;
  for (int i = 0; i < n; ++i) {
    const char c = s[*pos + i];
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
    v = v * 10 + (c - '0');
  }
  *value = v;
  *pos += n;
  return true;
}

/// NMEA 0183's ddmmyy (RMC); two-digit years 80..99 are 19yy, 00..79 20yy.
inline bool ParseDdMmYy(std::string_view s, std::int64_t* days) {
  std::size_t pos = 0;
  int d = 0, m = 0, yy = 0;
  if (s.size() != 6 || !ReadDigits(s, &pos, 2, &d) || !ReadDigits(s, &pos, 2, &m) ||
      !ReadDigits(s, &pos, 2, &yy)) {
    return false;
  }
  const int y = yy >= 80 ? 1900 + yy : 2000 + yy;
  if (!ValidDate(y, m, d)) return false;
  *days = DaysFromCivil(y, static_cast<unsigned>(m), static_cast<unsigned>(d));
  return true;
}

/// canboat's timestamps, UTC: `YYYY-MM-DDThh:mm:ss[.f...][Z]` (ISO 8601) or the older
/// `YYYY-MM-DD-hh:mm:ss[.f...]`, up to 9 decimals, into nanoseconds since the Unix epoch.
inline bool ParseIsoUtc(std::string_view s, TimeNs* t_ns) {
  std::size_t pos = 0;
  int y = 0, mo = 0, d = 0, h = 0, mi = 0, sec = 0;
  auto expect = [&](char c) { return pos < s.size() && s[pos++] == c; };
  if (!ReadDigits(s, &pos, 4, &y) || !expect('-') || !ReadDigits(s, &pos, 2, &mo) || !expect('-') ||
      !ReadDigits(s, &pos, 2, &d)) {
    return false;
  }
  if (pos >= s.size() || (s[pos] != 'T' && s[pos] != '-' && s[pos] != ' ')) return false;
  ++pos;
  if (!ReadDigits(s, &pos, 2, &h) || !expect(':') || !ReadDigits(s, &pos, 2, &mi) || !expect(':') ||
      !ReadDigits(s, &pos, 2, &sec)) {
    return false;
  }
  if (!ValidDate(y, mo, d) || h > 23 || mi > 59 || sec > 60) return false;
  // int64 nanoseconds since 1970 end in 2262 (a fuzzed year 7390 overflowed them).
  if (y < 1900 || y > 2200) return false;
  TimeNs fraction_ns = 0;
  if (pos < s.size() && s[pos] == '.') {
    ++pos;
    TimeNs scale = 1000000000;
    int digits = 0;
    while (pos < s.size() && std::isdigit(static_cast<unsigned char>(s[pos]))) {
      if (++digits > 9) return false;
      scale /= 10;
      fraction_ns += (s[pos++] - '0') * scale;
    }
    if (digits == 0) return false;
  }
  if (pos < s.size() && s[pos] == 'Z') ++pos;
  if (pos != s.size()) return false;
  const std::int64_t days = DaysFromCivil(y, static_cast<unsigned>(mo), static_cast<unsigned>(d));
  *t_ns = ((days * 24 + h) * 60 + mi) * 60 * 1000000000LL + sec * 1000000000LL + fraction_ns;
  return true;
}

}  // namespace skerry
