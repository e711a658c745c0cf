// The q-quantile of a sample by rank (no interpolation): the element that
// would stand at index floor(q * n) once sorted, so q = 0.5 is the upper
// median. Used wherever a robust location or spread of measurements is
// needed (ground fit, reconstruction check, row registration).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace orchard {

// 0 for an empty sample; q is clamped to the sample's range of ranks.
inline double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(std::max(0.0, q) * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace orchard
