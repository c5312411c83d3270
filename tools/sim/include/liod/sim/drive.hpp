#pragma once
// Turns a planned path into the vehicle's true motion: a speed profile bounded by lateral and
// longitudinal acceleration, a jerk-limited driver that follows it (with stops), the body's
// attitude from the terrain under its four wheels, suspension response to road roughness, body
// roll and pitch from load transfer, and engine/tyre vibration.

#include <cstdint>

#include "liod/sim/path.hpp"
#include "liod/sim/terrain.hpp"
#include "liod/sim/trajectory.hpp"

namespace liod::sim {

struct VehicleParams {
  double wheelbase = 2.8;         // m
  double track = 1.6;             // m
  double imu_height = 0.80;       // m above the road
  double max_lateral_accel = 3.0; // m/s^2
  double max_accel = 1.6;         // m/s^2
  double max_decel = 2.0;         // m/s^2 (planned; the driver may brake harder briefly)
  double max_jerk = 3.0;          // m/s^3
  double roughness = 32e-6;       // ISO 8608 displacement PSD at 0.1 cycle/m, m^3 (class A/B)
  double roll_per_lat_accel = 0.45;   // deg per m/s^2 (body leans out of the turn)
  double pitch_per_long_accel = 0.35; // deg per m/s^2 (squat / dive)
  double body_heave_hz = 1.3;
  double body_pitch_hz = 1.6;
  double body_roll_hz = 1.9;
  double body_damping = 0.35;
  // Road vibration on top of the suspension modes (liod-sim --vibration-scale), 0 = none; 1 is a
  // rough road: body bounce ~3 Hz of 4 mm, wheel hop ~11 Hz of 0.4 mm, pitch shake ~9 Hz of
  // 0.8 mrad, roll shake ~11 Hz of 0.4 mrad (amplitudes of each narrow band).
  double road_vibration = 0.0;
};

struct DriveStats {
  double distance = 0.0;
  double top_speed = 0.0;
  double peak_lateral_accel = 0.0;
  double peak_long_accel = 0.0;
  double peak_decel = 0.0;
  int stops = 0;
};

Trajectory generate_drive(const DrivePlan& plan, const PathCurve& path, const Terrain& terrain,
                          const VehicleParams& vehicle, double duration, std::uint64_t seed,
                          DriveStats* stats);

}  // namespace liod::sim
