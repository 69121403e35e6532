#include "skerry/geo/vertical_datum.h"

#include <stdexcept>

namespace skerry::geo {

std::string ToString(VerticalDatum datum) {
  switch (datum) {
    case VerticalDatum::kEgm96:
      return "egm96";
    case VerticalDatum::kEllipsoidal:
      return "ellipsoidal";
  }
  return "?";
}

VerticalDatum ParseVerticalDatum(const std::string& text) {
  if (text == "egm96") return VerticalDatum::kEgm96;
  if (text == "ellipsoidal") return VerticalDatum::kEllipsoidal;
  throw std::invalid_argument("vertical datum '" + text + "': expected egm96 or ellipsoidal");
}

}  // namespace skerry::geo
