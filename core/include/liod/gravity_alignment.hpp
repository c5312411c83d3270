#pragma once
// Initial attitude from the accelerometer: the mean specific force points opposite to gravity.
// At a rolling start the vehicle's own acceleration tilts this estimate, so the filter starts
// with a roll/pitch uncertainty and the LiDAR corrects it. The speed is not observable here at
// all (rest and steady cruising read the same): the odometry finds it from the first two scans.

#include <Eigen/Core>
#include <deque>
#include <optional>

#include "liod/types.hpp"

namespace liod {

struct GravityAlignment {
  Eigen::Matrix3d rotation;          // R_world_body with zero yaw
  Eigen::Vector3d gyro_bias;         // mean angular rate if the motion was steady, else zero
  bool steady = false;               // no vibration or turning: at rest or cruising straight
};

/// Uses the samples in [from, to]; nullopt with fewer than min_samples.
std::optional<GravityAlignment> align_gravity(const std::deque<ImuSample>& samples, double from, double to,
                                              std::size_t min_samples = 10);

/// The mean gyro reading over the samples in [from, to]; nullopt with fewer than min_samples.
std::optional<Eigen::Vector3d> mean_angular_rate(const std::deque<ImuSample>& samples, double from, double to,
                                                 std::size_t min_samples = 10);

/// The rotation with zero yaw that maps the body's measured "up" (specific force direction) to +z.
Eigen::Matrix3d rotation_from_up(const Eigen::Vector3d& up_in_body);

}  // namespace liod
