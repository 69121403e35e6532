#pragma once
// Internal to skerry_twin (not installed): the one median of the module's robust statistics.

#include <algorithm>
#include <vector>

namespace skerry::twin_internal {

// The median of v (the upper one, v[n / 2] of the sorted values, for an even count), by
// selection in O(n); 0 for an empty v.
inline double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace skerry::twin_internal
