#include "liod/imu_range.hpp"

#include <cmath>

namespace liod {

ImuReading classify(const ImuSample& sample, const ImuRange& range) noexcept {
  constexpr double kAtRange = 0.999;
  bool saturated = (sample.flags & ImuSample::kSaturated) != 0;
  const auto check = [&](const Eigen::Vector3d& v, double limit) {
    for (int k = 0; k < 3; ++k) {
      const double a = std::abs(v[k]);
      if (!std::isfinite(a) || a > limit) return false;
      saturated = saturated || a >= kAtRange * limit;
    }
    return true;
  };
  if (!check(sample.gyro, range.gyro_rad_s) || !check(sample.accel, range.accel_m_s2)) return ImuReading::OutOfRange;
  return saturated ? ImuReading::Saturated : ImuReading::Valid;
}

}  // namespace liod
