#pragma once
/// \file
/// A MarineLog (marine_log.h) made into a skerry Dataset without IMU: GNSS fixes in the local
/// ENU frame of the first fix, and the heading, course, attitude and rate-of-turn records
/// (docs/marine_logs.md, docs/dataset-format.md).

#include <map>
#include <string>

#include "skerry/io/dataset.h"
#include "skerry/io/marine_log.h"

namespace skerry {

/// The kinds of record, each from one source.
enum class MarineKind { kFix, kHeading, kCourse, kAttitude, kRateOfTurn };
const char* MarineKindName(MarineKind kind);  ///< fix, heading, course, attitude, rate_of_turn
/// false when `name` is none of MarineKindName's.
bool ParseMarineKind(const std::string& name, MarineKind* kind);

struct MarineDatasetOptions {
  /// The source to keep per kind (an NMEA 2000 `src` such as "25", an NMEA 0183 talker such as
  /// "GP"); a kind not listed keeps the source that sent the most records of it (ties: the
  /// smallest name).
  std::map<MarineKind, std::string> sources;
  std::string name;  ///< the dataset's; empty: the log's file name without its extensions
};

/// What the conversion kept and dropped, per kind.
struct MarineKindSelection {
  std::string source;  ///< the one kept (empty when the kind has no records)
  std::map<std::string, int> records_by_source;
  int kept = 0;
  int other_sources = 0;  ///< dropped: from the sources not kept
  int duplicates = 0;     ///< dropped: at the same time as the kept one before
};
using MarineSelection = std::map<MarineKind, MarineKindSelection>;

/// The dataset: origin at the first fix kept (its height, or the first height any fix has, or
/// 0 m), the WGS84 Earth, has_imu false, has_gnss true with the antenna at the body origin (the
/// logs do not say where it is), one fix per time from the chosen source (sigma_e, sigma_n,
/// sigma_u from the fix; a fix without height gets the origin's height and
/// kUnknownHeightSigmaM), and `marine` with one record per time per kind. Throws InputError
/// naming the log when no fix is left, or when `options` names a source that sent no record of
/// its kind.
Dataset MarineLogToDataset(const MarineLog& log,
                           const MarineDatasetOptions& options = {},
                           MarineSelection* selection = nullptr);

/// Figures of a fix track: count, first to last fix (s), mean rate (fixes - 1) / span (Hz, 0
/// for fewer than two), and horizontal length (sum of east-north distances between consecutive
/// fixes, m).
struct TrackFigures {
  int fixes = 0;
  double span_s = 0.0;
  double rate_hz = 0.0;
  double length_m = 0.0;
};
TrackFigures FixTrackFigures(const std::vector<GnssFix>& fixes);

}  // namespace skerry
