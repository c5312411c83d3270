// The IMU stops delivering for a while, or the body rocks at rest.
#include <cmath>
#include <string>

#include "faults.hpp"

namespace liod::fault {

std::string apply(const CutImu& f, Recording& r, Rng&) {
  const std::size_t before = r.imu.size();
  std::erase_if(r.imu, [&](const ImuSample& s) { return f.window.contains(r.seconds_of_imu(s.time)); });
  return "imu-cut: " + std::to_string(before - r.imu.size()) + " IMU samples removed";
}

std::string apply(const RockImu& f, Recording& r, Rng&) {
  constexpr double kPitchHz = 1.6;
  constexpr double kRollHz = 1.9;
  constexpr double kGravity = 9.80665;
  std::size_t rocked = 0;
  for (auto& s : r.imu) {
    const double t = r.seconds_of_imu(s.time);
    if (!f.window.contains(t)) continue;
    const double since = t - f.window.from_s;
    const double wp = 2.0 * M_PI * kPitchHz;
    const double wr = 2.0 * M_PI * kRollHz;
    // Angles (rate / w) sin(w t), rates rate cos(w t): from rest at the window's start.
    const double pitch = f.rate_rad_s / wp * std::sin(wp * since);
    const double roll = f.rate_rad_s / wr * std::sin(wr * since);
    s.gyro.x() += f.rate_rad_s * std::cos(wr * since);
    s.gyro.y() += f.rate_rad_s * std::cos(wp * since);
    // Gravity's reaction seen from the tilted body: R^T (0, 0, g) = (-g pitch, g roll, g) to first order.
    s.accel.x() -= kGravity * pitch;
    s.accel.y() += kGravity * roll;
    ++rocked;
  }
  return "rock: " + std::to_string(rocked) + " IMU samples rocked";
}

}  // namespace liod::fault
