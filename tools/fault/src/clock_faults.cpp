// A sensor clock steps forward or back.
#include <cmath>
#include <string>

#include "faults.hpp"
#include "liod/fault/helios_packet_edit.hpp"

namespace liod::fault {

std::string apply(const ClockJump& f, Recording& r, Rng&) {
  if (f.sensor == Sensor::Lidar) {
    const auto step_ns = static_cast<std::int64_t>(std::llround(f.by_s * 1e9));
    std::size_t shifted = 0;
    for (Packet& p : r.packets) {
      if (!is_msop(p.payload) || r.seconds_of(p.capture_time_ns) < f.at_s) continue;
      set_msop_time_ns(p.payload, msop_time_ns(p.payload) + step_ns);
      ++shifted;
    }
    return "clock-jump: LiDAR header time of " + std::to_string(shifted) + " MSOP packets moved by " +
           std::to_string(f.by_s) + " s";
  }
  std::vector<ImuSample> out;
  out.reserve(r.imu.size());
  std::size_t shifted = 0;
  for (ImuSample s : r.imu) {
    if (r.seconds_of_imu(s.time) >= f.at_s) {
      s.time += f.by_s;
      ++shifted;
    }
    // A step back repeats times already delivered: liod's IMU drivers pass on increasing times only.
    if (!out.empty() && s.time <= out.back().time) continue;
    out.push_back(s);
  }
  const std::size_t dropped = r.imu.size() - out.size();
  r.imu = std::move(out);
  return "clock-jump: IMU stamps of " + std::to_string(shifted) + " samples moved by " + std::to_string(f.by_s) +
         " s, " + std::to_string(dropped) + " no longer increasing dropped";
}

}  // namespace liod::fault
