#pragma once
/// \file
/// A model parameter identified from data: its value and the 1-sigma uncertainty of that value
/// (what twin.yaml writes for every parameter, docs/twin.md).

namespace skerry {

struct IdentifiedValue {
  double value = 0.0;
  double sigma = 0.0;       ///< 1-sigma uncertainty of `value`; 0 when not known
  bool identified = false;  ///< false: the data did not determine it (value is a default)
};

}  // namespace skerry
