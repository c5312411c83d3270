#include "liod/gravity_alignment.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>

namespace liod {

Eigen::Matrix3d rotation_from_up(const Eigen::Vector3d& up_in_body) {
  const Eigen::Vector3d up = up_in_body.normalized();
  // Roll and pitch that level the body; yaw is unobservable and set to zero.
  const double roll = std::atan2(up.y(), up.z());
  const double pitch = std::atan2(-up.x(), std::sqrt(up.y() * up.y() + up.z() * up.z()));
  return (Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

namespace {

// The mean of one of the samples' readings over [from, to], with how many samples it took.
std::optional<std::pair<Eigen::Vector3d, std::size_t>> mean_reading(const std::deque<ImuSample>& samples, double from,
                                                                    double to, std::size_t min_samples,
                                                                    Eigen::Vector3d ImuSample::*reading) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (const auto& s : samples) {
    if (s.time < from || s.time > to) continue;
    sum += s.*reading;
    ++n;
  }
  if (n < std::max<std::size_t>(min_samples, 1)) return std::nullopt;
  return std::make_pair(Eigen::Vector3d(sum / static_cast<double>(n)), n);
}

}  // namespace

std::optional<Eigen::Vector3d> mean_angular_rate(const std::deque<ImuSample>& samples, double from, double to,
                                                 std::size_t min_samples) {
  const auto mean = mean_reading(samples, from, to, min_samples, &ImuSample::gyro);
  if (!mean) return std::nullopt;
  return mean->first;
}

std::optional<GravityAlignment> align_gravity(const std::deque<ImuSample>& samples, double from, double to,
                                              std::size_t min_samples) {
  const auto accel = mean_reading(samples, from, to, min_samples, &ImuSample::accel);
  const auto gyro_mean = mean_angular_rate(samples, from, to, min_samples);
  if (!accel || !gyro_mean) return std::nullopt;
  const Eigen::Vector3d& accel_mean = accel->first;
  const std::size_t n = accel->second;
  double accel_var = 0.0;
  double gyro_max = 0.0;
  for (const auto& s : samples) {
    if (s.time < from || s.time > to) continue;
    accel_var += (s.accel - accel_mean).squaredNorm();
    gyro_max = std::max(gyro_max, s.gyro.norm());
  }
  accel_var /= static_cast<double>(n);
  GravityAlignment out;
  out.rotation = rotation_from_up(accel_mean);
  // Little vibration and no turning: standing still, or cruising straight (the IMU cannot tell
  // the two apart). Either way the mean rate is the gyro bias.
  out.steady = accel_var < 0.05 && gyro_max < 0.05;
  out.gyro_bias = out.steady ? *gyro_mean : Eigen::Vector3d::Zero();
  return out;
}

}  // namespace liod
