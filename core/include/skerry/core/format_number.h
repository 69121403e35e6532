#pragma once
/// \file
/// A number as a message shows it: the shortest of fixed and exponent notation with six
/// significant digits (printf's %g), as the bounds in the readers' errors are written.

#include <sstream>
#include <string>

namespace skerry {

inline std::string FormatNumber(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace skerry
