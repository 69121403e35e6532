#pragma once
/// \file
/// A configuration named on the command line with keys changed: `SOURCE,KEY=VALUE,...`, the
/// preset or YAML file SOURCE with each KEY=VALUE applied as `--set` applies it (e.g.
/// `default,skyline.dem_sharpening_sigma=1`). `skerry compare` takes these as `--config`, so
/// that variants of one preset compare without a YAML file per variant (docs/compare.md).

#include <string>
#include <vector>

#include "skerry/solvers/estimator_config.h"

namespace skerry::cli {

struct ConfigVariant {
  std::string source;                  ///< preset name or YAML file
  std::vector<std::string> overrides;  ///< KEY=VALUE, in the order given
};

/// Splits `text` at its commas, except those inside [] or {} (a YAML list or map is one value).
/// A `text` that names an existing file is that file with no overrides, commas and all.
/// An empty source or an empty part is an InputError naming `field`.
ConfigVariant ParseConfigVariant(const std::string& text, const std::string& field);

/// The configuration `text` stands for (ParseConfigVariant, then LoadPreset). With overrides
/// and none of them `name`, it is named after its source and changes, e.g.
/// `default-dem_sharpening_sigma-1` (the last part of each key and its value, characters a
/// folder name cannot hold as '_'), so variants of one preset have names of their own.
EstimatorConfig LoadConfigVariant(const std::string& text, const std::string& field);

}  // namespace skerry::cli
