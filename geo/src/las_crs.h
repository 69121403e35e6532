#pragma once
// The CRS of a LAS file from its LASF_Projection records (private to skerry_geo).

#include <string>
#include <vector>

#include "skerry/geo/las_reader.h"

namespace skerry::geo::internal {

struct DecodedCrs {
  std::string wkt;   ///< WKT2, empty when not decoded
  std::string note;  ///< where it came from, or why it was not decoded
};

/// OGC WKT (record 2112) if present and readable, else the GeoTIFF keys (34735, with 34736 /
/// 34737): EPSG codes of ProjectedCSTypeGeoKey (3072) or GeographicTypeGeoKey (2048), the
/// linear unit of ProjLinearUnitsGeoKey (3076) overriding the code's own.
DecodedCrs DecodeLasCrs(const std::vector<LasVlr>& vlrs);

}  // namespace skerry::geo::internal
