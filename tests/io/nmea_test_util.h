#pragma once
// NMEA 0183 sentences for tests: a body with its right checksum.

#include <cstdio>
#include <string>

#include "skerry/io/nmea0183.h"

namespace skerry::testing {

/// `$BODY*hh` with the right checksum.
inline std::string WithChecksum(const std::string& body) {
  char hex[4];
  std::snprintf(hex, sizeof(hex), "%02X", nmea0183::Checksum(body));
  return "$" + body + "*" + hex;
}

}  // namespace skerry::testing
