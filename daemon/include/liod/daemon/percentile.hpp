#pragma once
#include <algorithm>
#include <vector>

namespace liod {

/// The q-quantile (0..1, nearest rank below) of the values; 0 for none.
inline double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(q * static_cast<double>(values.size() - 1))];
}

}  // namespace liod
