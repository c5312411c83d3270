#pragma once
// The road as hard as a real one (issue 56): conditions liod-sim adds to a drive, each one a
// switch, all of them at once with --hard. Off by default: a drive without them is byte for byte
// what it was before they existed.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "liod/sim/scene.hpp"
#include "liod/sim/trajectory.hpp"

namespace liod::sim {

struct RoadConditions {
  bool traffic = false;          // vehicles in the other lanes and ahead (traffic.hpp)
  bool wind = false;             // porous vegetation sways (wind.cpp)
  bool open_stretch = false;     // ~100 m of the route with only ground and a hedge
  double vibration_scale = 0.0;  // road vibration: body bounce ~3 Hz, wheel hop ~11 Hz, pitch shake ~9 Hz
  bool consumer_imu = false;     // a Bosch BMI088 instead of the default MEMS unit
  double dropout = 0.0;          // fraction of returns lost at random
  double rain_rate = 0.0;        // spurious near returns per second

  bool any() const {
    return traffic || wind || open_stretch || vibration_scale > 0.0 || consumer_imu || dropout > 0.0 ||
           rain_rate > 0.0;
  }
  /// The hard drive: every condition on.
  static RoadConditions hard() {
    RoadConditions c;
    c.traffic = true;
    c.wind = true;
    c.open_stretch = true;
    c.vibration_scale = 1.0;
    c.consumer_imu = true;
    c.dropout = 0.03;
    c.rain_rate = 1000.0;
    return c;
  }
};

/// The stretch of route cleared of structure.
struct OpenStretch {
  double t_begin = 0.0;  // when the car enters and leaves it
  double t_end = 0.0;
  std::vector<Eigen::Vector2d> path;  // the car's lane through it, 1 m apart
  std::size_t removed = 0;            // primitives taken out
  std::size_t hedge = 0;              // hedge boxes put in
};

/// Clears about 100 m of the route that the car drives between 30 and 55 % of the drive:
/// every primitive within kOpenClearance of it goes, and a hedge lines its right side. Call
/// World::rebuild() afterwards.
OpenStretch clear_open_stretch(Scene& scene, const Trajectory& ego, double duration, std::uint64_t seed);

inline constexpr double kOpenLength = 100.0;    // m
inline constexpr double kOpenClearance = 45.0;  // m either side

}  // namespace liod::sim
