#pragma once
// Configs and datasheets state angles in degrees; the code works in radians.

#include <numbers>

namespace liod {

inline constexpr double kDegToRad = std::numbers::pi / 180.0;

}  // namespace liod
