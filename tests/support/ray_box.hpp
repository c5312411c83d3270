#pragma once
// Where a ray meets an axis-aligned box, for tests that cast synthetic scans at posts.
#include <Eigen/Core>

#include <algorithm>
#include <optional>

namespace liod::test {

/// Where the ray origin + t dir (t >= 0) enters the axis-aligned box [lo, hi] (slab method: where
/// it has entered both slabs), if it meets the box.
inline std::optional<double> box_entry(const Eigen::Vector2d& origin, const Eigen::Vector2d& dir,
                                       const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  double enter = 0.0;
  double leave = 1e9;
  for (int a = 0; a < 2; ++a) {
    const double t0 = (lo(a) - origin(a)) / dir(a);
    const double t1 = (hi(a) - origin(a)) / dir(a);
    enter = std::max(enter, std::min(t0, t1));
    leave = std::min(leave, std::max(t0, t1));
  }
  if (enter > leave) return std::nullopt;
  return enter;
}

}  // namespace liod::test
