#pragma once
/// \file
/// CLI11 checks of a number option that also refuse what is not finite. CLI11's own number
/// checks (PositiveNumber, NonNegativeNumber, Range) compare, and every comparison with NaN is
/// false, so `--rpe-delta nan` passed them and printed "RPE over nan s: 0.000 m"; their messages
/// also print the largest double in full.

#include <CLI/CLI.hpp>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace skerry::cli {

/// Finite, at least `lo` (above it when `lo_open`) and at most `hi` (no upper bound when hi is
/// infinite).
inline CLI::Validator FiniteNumber(double lo = -std::numeric_limits<double>::infinity(),
                                   double hi = std::numeric_limits<double>::infinity(),
                                   bool lo_open = false) {
  return CLI::Validator(
      [lo, hi, lo_open](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return "not a number: " + text;
        const bool above = lo_open ? value > lo : value >= lo;
        if (std::isfinite(value) && above && value <= hi) return std::string();
        std::ostringstream os;
        os << "must be a finite number";
        if (std::isfinite(lo)) os << (lo_open ? " > " : " >= ") << lo;
        if (std::isfinite(lo) && std::isfinite(hi)) os << " and";
        if (std::isfinite(hi)) os << " <= " << hi;
        os << ", is " << text;
        return os.str();
      },
      "NUMBER");
}

}  // namespace skerry::cli
