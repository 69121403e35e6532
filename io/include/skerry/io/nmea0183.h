#pragma once
/// \file
/// NMEA 0183 log files: one sentence a line (docs/marine_logs.md).
///
/// A line may carry anything before its sentence, such as a logger's timestamp
/// (`2024-05-01T10:00:00.123Z $GPGGA,...`, `1714557600.123,$GPGGA,...`) or an NMEA 4.10 TAG
/// block (`\s:GPS,c:1714557600*5B\$GPGGA,...`): the sentence starts at the first `$` or `!` and
/// the prefix is not read. Times are the receiver's own: GGA's and GST's time of day on the date
/// of RMC. Lines may end in LF or CRLF; the file may be gzip-compressed.
///
/// Sentence types are talker-independent (GPGGA, GNGGA, INGGA, ... are all GGA): GGA, RMC, VTG,
/// HDT, THS and GST are read; other well-formed sentences are counted as ignored by type.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "skerry/core/time.h"
#include "skerry/io/marine_log.h"

namespace skerry::nmea0183 {

/// GGA: fix data. Quality 1 and 3 (GPS, PPS) are autonomous, 2 and 9 (DGPS, SBAS) differential,
/// 4 RTK fixed, 5 RTK float; 0 (none), 6 (estimated), 7 (manual) and 8 (simulator) are not
/// measurements (BadReason::kInvalidFix).
struct Gga {
  TimeNs time_of_day_ns = 0;  ///< since UTC midnight
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  int quality = 0;
  FixKind kind = FixKind::kAutonomous;
  std::optional<double> hdop;                ///< absent when the field is empty
  std::optional<double> altitude_msl_m;      ///< orthometric (above the geoid)
  std::optional<double> geoid_separation_m;  ///< ellipsoid height = altitude + separation
};

/// RMC: recommended minimum data, status A (status V, or mode N/E, is kInvalidFix).
struct Rmc {
  TimeNs time_of_day_ns = 0;
  std::int64_t days_since_epoch = 0;  ///< the UTC date (ddmmyy, years 80..99 -> 19yy)
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  std::optional<double> sog_m_s;  ///< from knots; absent when empty
  std::optional<double> cog_deg;  ///< true; absent when empty (often at rest)
};

/// VTG: true course and speed over ground (mode N or E is kInvalidFix).
struct Vtg {
  double cog_deg = 0.0;
  double sog_m_s = 0.0;  ///< from knots
};

/// HDT: true heading.
struct Hdt {
  double heading_deg = 0.0;
};

/// THS: true heading and mode; only mode A (autonomous) is a measurement: E (estimated),
/// M (manual), S (simulator) and V (invalid) are kInvalidFix.
struct Ths {
  double heading_deg = 0.0;
};

/// GST: the receiver's 1-sigma errors of latitude, longitude and altitude, metres.
struct Gst {
  TimeNs time_of_day_ns = 0;
  double sigma_lat_m = 0.0;
  double sigma_lon_m = 0.0;
  double sigma_alt_m = 0.0;
};

/// A sentence that parsed, with its talker (GP, GN, ...) and type (GGA, ...).
struct Sentence {
  std::string talker;
  std::string type;
  std::variant<Gga, Rmc, Vtg, Hdt, Ths, Gst> data;
};

/// A sentence that is bad, and why; `type` is "?" when the address is unreadable.
struct Rejected {
  std::string type;
  BadReason reason;
};

/// A well-formed sentence of a type not read here (GSV, proprietary $P..., AIS !AIVDM, ...).
struct Ignored {
  std::string type;
};

using ParseResult = std::variant<Sentence, Rejected, Ignored>;

/// The NMEA checksum: XOR of the characters between `$` (or `!`) and `*`, i.e. of `body`.
std::uint8_t Checksum(std::string_view body);

/// Parses one line of a log (prefix, sentence, optional `*hh`). In order: a line without `$`/`!`
/// is kNotASentence; `*` followed by fewer than two characters is kTruncated, by anything but
/// two hex digits or by the wrong checksum kChecksumMismatch; without `*`, a sentence of a type
/// read here with fewer fields than the type has is kTruncated, any other kMissingChecksum.
/// Then the field count (kFieldCount), empty required fields (kEmptyField), fields that do not
/// parse (kBadNumber), NaN/Inf (kNonFinite), latitudes and longitudes outside their ranges
/// (kOutOfRange) and invalid fixes or modes (kInvalidFix).
ParseResult ParseLine(std::string_view line);

/// `ddmm.mmmm` (latitude) or `dddmm.mmmm` (longitude) and its hemisphere letter, in degrees,
/// computed from the digits (4807.038,N -> 48 + 7.038 / 60); nullopt when malformed.
std::optional<double> ParseCoordinate(std::string_view value, std::string_view hemisphere);

/// `hhmmss[.s...]` in nanoseconds since midnight (exact, up to 9 decimals); nullopt when
/// malformed.
std::optional<TimeNs> ParseTimeOfDay(std::string_view value);

/// Reads a log (plain or gzip). The date comes from RMC: sentences before the first valid RMC
/// take its date (the day before when their time of day is more than 12 h after it); after it,
/// a time of day more than 12 h before the previous one is the next day (midnight), and every
/// RMC sets the date. A time before the previous one is kTimeBackwards and the sentence is
/// dropped. VTG, HDT and THS carry no time: they get the time of the last timed sentence (one
/// epoch late at most when a receiver sends them first); kNoTime before any. GST sets the sigmas
/// of the GGA fix at the same time; fixes without GST get sigmas from HDOP (SetSigmasFromHdop)
/// or assumed ones. RMC positions become fixes only in a log without any GGA. Never throws for
/// bad content; throws InputError when the file cannot be opened or read.
MarineLog ReadLog(const std::string& path);

}  // namespace skerry::nmea0183
