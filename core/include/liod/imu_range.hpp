#pragma once
// The plausibility gate every IMU sample passes on its way in, whatever its transport. A reading
// beyond the sensor's measurement range is no measurement: it is corruption that passed the
// transport's checks (an 8-bit checksum lets 1 in 256 corrupted messages through, a CAN signal
// table any value its field holds). A reading at the range is the sensor clipping: the true
// value was that or more.

#include <cstdint>
#include <limits>

#include "liod/types.hpp"

namespace liod {

/// The largest magnitude each axis can measure (the datasheet's full range).
struct ImuRange {
  double gyro_rad_s = std::numeric_limits<double>::infinity();
  double accel_m_s2 = std::numeric_limits<double>::infinity();
};

enum class ImuReading : std::uint8_t { Valid, Saturated, OutOfRange };

/// OutOfRange when an axis is not finite or beyond its range. Saturated when an axis reaches its
/// range (to within 0.1 %, the resolution a logged or CAN-scaled reading keeps) or the sample
/// already carries ImuSample::kSaturated (the sensor reported the clip). Else Valid.
[[nodiscard]] ImuReading classify(const ImuSample& sample, const ImuRange& range) noexcept;

}  // namespace liod
