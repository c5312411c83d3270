// The IMU stops delivering for a while.
#include <string>

#include "faults.hpp"

namespace liod::fault {

std::string apply(const CutImu& f, Recording& r, Rng&) {
  const std::size_t before = r.imu.size();
  std::erase_if(r.imu, [&](const ImuSample& s) { return f.window.contains(r.seconds_of_imu(s.time)); });
  return "imu-cut: " + std::to_string(before - r.imu.size()) + " IMU samples removed";
}

}  // namespace liod::fault
