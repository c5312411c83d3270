#pragma once
// A beam's unit direction in the LiDAR frame from its elevation and azimuth (radians), as the
// RS-Helios spec's point formula (x forward, y left, z up) has it.

#include <Eigen/Core>
#include <cmath>

namespace liod::test {

inline Eigen::Vector3d beam_direction(double elevation, double azimuth) {
  return {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation)};
}

}  // namespace liod::test
