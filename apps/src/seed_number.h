#pragma once
/// \file
/// The CLI11 check of a random seed option. CLI11 reads integers with strtoull / strtoll and
/// does not look at their range errors: `--seed 99999999999999999999` became the largest
/// integer, and `--seed -5` a seed of 2^64 - 5 (or, for `simulate`, "not given": the
/// scenario's own seed, silently).

#include <CLI/CLI.hpp>
#include <charconv>
#include <cstdint>
#include <limits>
#include <string>

namespace skerry::cli {

/// Decimal digits only, at most `max` (2^64 - 1 unless the option's type holds less).
inline CLI::Validator SeedNumber(std::uint64_t max = std::numeric_limits<std::uint64_t>::max()) {
  return CLI::Validator(
      [max](std::string& text) -> std::string {
        std::uint64_t value = 0;
        const char* end = text.data() + text.size();
        const auto result = std::from_chars(text.data(), end, value);
        if (text.empty() || result.ec != std::errc() || result.ptr != end || value > max) {
          return "must be a whole number from 0 to " + std::to_string(max) + ", is " + text;
        }
        return std::string();
      },
      "SEED");
}

}  // namespace skerry::cli
