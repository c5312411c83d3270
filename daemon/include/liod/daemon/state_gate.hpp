#pragma once
// The last check before a pose goes out as `ok`: the filter's flags say how well the scan
// constrained it, not whether the numbers themselves can be true. A state with a NaN, a speed
// no road vehicle reaches, a bias no IMU has, or a covariance that is not positive definite
// (a filter that lost its numerical footing) is published flagged `implausible` and never `ok`
// (docs/pose-protocol.md). The checks are core's (state_sanity.hpp): the odometry re-initialises
// from a scan state that fails them, with the same limits (Pipeline hands them over); this gate
// makes sure that nobody steers by such a state meanwhile, nor by an IMU-rate pose that the IMU
// carried beyond them.

#include <Eigen/Core>
#include <cstdint>

#include "liod/config.hpp"
#include "liod/imu_preintegration.hpp"
#include "liod/state_sanity.hpp"

namespace liod {

const char* to_string(StateFault fault);

StateLimits state_limits(const Config& config);

}  // namespace liod
