#pragma once
/// \file
/// The vertical datum of the heights in a map or cloud file. skerry works in ellipsoidal heights
/// (WGS84, docs/dataset-format.md); every loader is told which datum its file uses, never guesses.

#include <string>

namespace skerry::geo {

enum class VerticalDatum {
  /// Orthometric heights above the EGM96 geoid (SRTM, most national DEMs as an approximation):
  /// the loader adds the geoid undulation N, h = H + N.
  kEgm96,
  /// Heights above the WGS84 ellipsoid: used as they are.
  kEllipsoidal,
};

/// "egm96" or "ellipsoidal" (the spelling of the dataset format's `vertical_datum:` key).
std::string ToString(VerticalDatum datum);

/// Parses ToString's spelling; throws std::invalid_argument for anything else.
VerticalDatum ParseVerticalDatum(const std::string& text);

}  // namespace skerry::geo
