#pragma once
/// \file
/// NMEA 2000 as canboat's analyzer decodes it to JSON lines (`analyzer -json -si`), plain or
/// gzip-compressed (docs/marine_logs.md). The first line is a header object with
/// `"units":"si"` (angles in radians, speeds m/s, latitude and longitude in degrees); every
/// further line is one message: `"timestamp"` (UTC, `2026-08-03T04:47:01.298Z` or canboat's
/// older `2011-11-24-22:42:04.388`), `"pgn"`, `"src"` and `"fields"`.
///
/// PGNs read: 129025 Position Rapid Update, 129029 GNSS Position Data (altitude, HDOP, method),
/// 129026 COG & SOG Rapid Update, 127250 Vessel Heading, 127257 Attitude, 127251 Rate of Turn;
/// others are counted as ignored by PGN. Time is the `timestamp` (the logger's reception time)
/// for every PGN, so that all records share one clock.

#include <string>

#include "skerry/io/marine_log.h"

namespace skerry::nmea2000 {

/// Reads a canboat JSON log. Each record keeps its source address (`src`) as MarineFix::source
/// etc.; choosing among sources is MarineLogToDataset's (marine_dataset.h). Per line and never
/// fatal, counted by PGN (type "129025", ..., or "?" when the line has no usable `pgn`) and
/// reason: a line that is not a JSON object (kMalformedJson); no `timestamp`, `pgn`, `src` or
/// `fields`, or a field a record needs (kMissingField); a value of the wrong type or a timestamp
/// that does not parse (kBadNumber); NaN or infinity (kNonFinite: JSON has neither, so
/// a line with `NaN` or an overflowing `1e999` is kMalformedJson); a latitude, longitude,
/// altitude (|h| > 100 km) or HDOP (<= 0) out of range (kOutOfRange); a 129029 whose method is
/// not a fix (no GNSS, estimated, manual, simulated: kInvalidFix); a magnetic 127250 without
/// variation or a magnetic 129026 (kMagneticNoVariation); a timestamp before the latest earlier
/// one, whatever its PGN (kTimeBackwards, the line dropped). 127250 magnetic headings are made true
/// as heading + deviation (0 when absent) + variation. 129025 fixes have no height and assumed
/// sigmas; 129029 fixes take Altitude as ellipsoidal (NMEA 2000 defines it on WGS84) and sigmas
/// from HDOP and Method (GNSS fix: autonomous, DGNSS fix: differential, Precise GNSS: differential,
/// RTK Fixed Integer, RTK float).
///
/// Throws InputError naming the file when it cannot be opened or read, when its header says
/// other units than "si", and when no line of it is a canboat record (not canboat JSON at all).
MarineLog ReadCanboatJson(const std::string& path);

}  // namespace skerry::nmea2000
