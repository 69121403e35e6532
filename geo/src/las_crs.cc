#include "las_crs.h"

#include <cmath>
#include <cstring>
#include <map>
#include <utility>

#include "gdal_support.h"

namespace skerry::geo::internal {
namespace {

constexpr const char* kProjectionUserId = "LASF_Projection";
constexpr int kUserDefined = 32767;

// GeoTIFF key ids (GeoTIFF 1.0 specification, section 6.2).
constexpr int kGtModelTypeGeoKey = 1024;
constexpr int kGeographicTypeGeoKey = 2048;
constexpr int kProjectedCsTypeGeoKey = 3072;
constexpr int kProjLinearUnitsGeoKey = 3076;
constexpr int kVerticalCsTypeGeoKey = 4096;

const LasVlr* Find(const std::vector<LasVlr>& vlrs, int record_id) {
  for (const LasVlr& v : vlrs) {
    if (v.user_id == kProjectionUserId && v.record_id == record_id) return &v;
  }
  return nullptr;
}

// Name and metres per unit of EPSG linear unit codes; {nullptr, 0} when unknown.
std::pair<const char*, double> LinearUnit(int code) {
  switch (code) {
    case 9001:
      return {"metre", 1.0};
    case 9002:
      return {"foot", 0.3048};
    case 9003:
      return {"US survey foot", 1200.0 / 3937.0};
    case 9005:
      return {"Clarke's foot", 0.3047972654};
    case 9036:
      return {"kilometre", 1000.0};
    default:
      return {nullptr, 0.0};
  }
}

DecodedCrs FromWkt(const LasVlr& vlr) {
  std::string text(vlr.data.begin(), vlr.data.end());
  text = text.substr(0, std::strlen(text.c_str()));  // up to the terminating NUL
  OGRSpatialReference crs;
  QuietGdalErrors quiet;
  // WKT alone (1 or 2, as the LAS 1.4 spec says the record holds): SetFromUserInput would also
  // take a file name, a URL or a PROJ string from the file, and GDAL would open or fetch it.
  if (crs.importFromWkt(text.c_str()) != OGRERR_NONE || crs.IsEmpty()) {
    return {"",
            "the OGC WKT record (2112) cannot be parsed as WKT" + QuietGdalErrors::LastMessage()};
  }
  return {CrsWkt(crs), "LAS OGC WKT record (2112): " + CrsName(crs)};
}

DecodedCrs FromGeoKeys(const LasVlr& directory) {
  const size_t shorts = directory.data.size() / 2;
  std::vector<std::uint16_t> d(shorts);
  std::memcpy(d.data(), directory.data.data(), shorts * 2);
  if (shorts < 4 || shorts < 4 + 4 * static_cast<size_t>(d[3])) {
    return {"", "the GeoKeyDirectory record (34735) is shorter than its key count"};
  }
  std::map<int, int> keys;  // id -> value, for keys stored in the directory itself (location 0)
  for (int k = 0; k < d[3]; ++k) {
    const std::uint16_t* e = &d[4 + 4 * k];
    if (e[1] == 0) keys[e[0]] = e[3];
  }
  const auto get = [&](int id) { return keys.count(id) ? keys.at(id) : -1; };

  std::string vertical;
  if (const int v = get(kVerticalCsTypeGeoKey); v > 0 && v != kUserDefined) {
    vertical = "; vertical CS EPSG:" + std::to_string(v) + " (not used: state the vertical datum)";
  }
  const int model = get(kGtModelTypeGeoKey);
  const int projected = get(kProjectedCsTypeGeoKey);
  const int geographic = get(kGeographicTypeGeoKey);
  OGRSpatialReference crs;
  std::string note;
  QuietGdalErrors quiet;
  if (projected > 0 && projected != kUserDefined) {
    if (crs.importFromEPSG(projected) != OGRERR_NONE) {
      return {"", "GeoTIFF keys: ProjectedCSTypeGeoKey " + std::to_string(projected) +
                      " is not an EPSG CRS PROJ knows" + QuietGdalErrors::LastMessage()};
    }
    note = "LAS GeoTIFF keys: EPSG:" + std::to_string(projected);
    if (const int unit = get(kProjLinearUnitsGeoKey); unit > 0) {
      const auto [name, metres] = LinearUnit(unit);
      if (name == nullptr) {
        return {"", "GeoTIFF keys: ProjLinearUnitsGeoKey " + std::to_string(unit) +
                        " is not a linear unit skerry knows (9001 metre, 9002 foot, 9003 US "
                        "survey foot, 9005 Clarke's foot, 9036 kilometre)"};
      }
      if (std::abs(crs.GetLinearUnits() - metres) > 1e-12 * metres) {
        // The unit key overrides the code's own unit (as libgeotiff reads it): x/y/z in feet
        // on a metre CRS is a common LAS writer convention.
        crs.SetLinearUnitsAndUpdateParameters(name, metres);
        note += std::string(" with its linear unit overridden to ") + name +
                " by ProjLinearUnitsGeoKey";
      }
    }
  } else if (geographic > 0 && geographic != kUserDefined && model != 1) {
    if (crs.importFromEPSG(geographic) != OGRERR_NONE) {
      return {"", "GeoTIFF keys: GeographicTypeGeoKey " + std::to_string(geographic) +
                      " is not an EPSG CRS PROJ knows" + QuietGdalErrors::LastMessage()};
    }
    note = "LAS GeoTIFF keys: EPSG:" + std::to_string(geographic);
  } else {
    const int code = projected > 0 ? projected : geographic;
    return {"", "GeoTIFF keys: " +
                    std::string(code == kUserDefined ? "a user-defined CRS (code 32767)"
                                                     : "no ProjectedCSTypeGeoKey or "
                                                       "GeographicTypeGeoKey") +
                    " is not decoded; give the CRS to PointCloudToEnu" + vertical};
  }
  return {CrsWkt(crs), note + vertical};
}

}  // namespace

DecodedCrs DecodeLasCrs(const std::vector<LasVlr>& vlrs) {
  EnsureGdalRegistered();
  std::string problems;
  if (const LasVlr* wkt = Find(vlrs, 2112)) {
    DecodedCrs out = FromWkt(*wkt);
    if (!out.wkt.empty()) return out;
    problems = out.note + "; ";
  }
  if (const LasVlr* keys = Find(vlrs, 34735)) {
    DecodedCrs out = FromGeoKeys(*keys);
    out.note = problems + out.note;
    return out;
  }
  return {"", problems +
                  "no CRS record (LASF_Projection 2112 or 34735); give the CRS to "
                  "PointCloudToEnu"};
}

}  // namespace skerry::geo::internal
