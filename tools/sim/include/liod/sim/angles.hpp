#pragma once
// Degrees to radians for the simulator's datasheet figures (the simulator keeps its own, as it
// shares no code with the estimator it tests).

#include <numbers>

namespace liod::sim {

inline constexpr double kDeg = std::numbers::pi / 180.0;

}  // namespace liod::sim
