#pragma once
// Whether the IMU says the vehicle is rolling: a car's body sits on its springs with heave, pitch
// and roll modes at 1-2 Hz, and the road's unevenness excites them only while the wheels turn. At
// a standstill the roll and pitch rates are the gyro's noise and the engine's vibration, which lies
// above 10 Hz and averages out over a few hundredths of a second. The LiDAR alone can mistake a
// rolling start for a standstill where what it sees moves with the sensor (a car parked beside the
// road, half hidden by the ego car's own roof); the rocking tells the two apart.

#include <Eigen/Core>
#include <deque>

#include "liod/types.hpp"

namespace liod {

enum class BodyMotion {
  kUnknown,  // too little of the IMU to tell
  kStill,
  kRocking,  // rolling on a road
};

struct BodyRockingParams {
  double window_s = 1.0;   // the IMU's last this much is judged
  double min_span_s = 0.5;  // with less than this, kUnknown
  double average_s = 0.05;  // the gyro is averaged over this before its spread is taken
  /// White-noise density of the gyro (rad/s/sqrt(Hz)): its share of the spread is expected at rest.
  double gyro_noise_density = 0.0;
  /// Rocking when the spread's square exceeds twice the noise's variance by this squared (rad/s).
  /// On liod-sim's drives the spread is 0.6-0.8 mrad/s at rest and 6-34 mrad/s under way; with
  /// liod.yaml's noise density the bound is 4.9 mrad/s.
  double rocking_rate_rad_s = 0.002;
};

/// The spread (rad/s) of the body's roll-and-pitch rate, i.e. the gyro less its component along
/// up_body: the root mean square about their mean of its average_s means over the window ending
/// at `to`. A steady turn (any axis) adds nothing. Negative if less than min_span_s of samples.
double rocking_rate(const std::deque<ImuSample>& samples, double to, const Eigen::Vector3d& up_body,
                    const BodyRockingParams& params);

BodyMotion body_motion(const std::deque<ImuSample>& samples, double to, const Eigen::Vector3d& up_body,
                       const BodyRockingParams& params);

}  // namespace liod
