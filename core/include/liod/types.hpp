#pragma once
// The data that crosses every boundary in liod: LiDAR scans and IMU samples.
// Times are seconds (double) on the IMU clock unless a field says otherwise.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace liod {

/// One LiDAR return in the sensor frame (x forward, y left, z up).
struct LidarPoint {
  float x = 0.0F;
  float y = 0.0F;
  float z = 0.0F;
  float intensity = 0.0F;
  /// Seconds after the owning Scan::start_time at which this point was measured.
  float time = 0.0F;
  /// Beam index ordered by elevation, 0 = lowest beam.
  std::uint16_t ring = 0;
  /// 0 = first/strongest return of a firing, 1 = second return (dual-return mode).
  std::uint8_t return_index = 0;
};

/// One full sensor revolution.
struct Scan {
  /// Time of the earliest point, in seconds (sensor clock as decoded).
  double start_time = 0.0;
  /// Time of the latest point.
  double end_time = 0.0;
  /// Increments by one per assembled sweep.
  std::uint64_t sequence = 0;
  /// Number of beams of the sensor that produced the scan (rings are < beam_count).
  std::uint16_t beam_count = 0;
  std::vector<LidarPoint> points;
};

/// One IMU measurement in the IMU (body) frame.
struct ImuSample {
  double time = 0.0;
  /// Angular rate, rad/s.
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
  /// Specific force (includes the reaction to gravity: +9.81 on z when level and at rest), m/s^2.
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
  /// What the driver found about this sample (the bits below); 0 for a plain measurement.
  std::uint8_t flags = 0;
  /// An axis reached the sensor's measurement range: it clipped, and reads a bound, not the motion.
  static constexpr std::uint8_t kSaturated = 1U << 0;
};

}  // namespace liod
