#pragma once
// The IMU samples the front end holds for the coming scans, and where the IMU was silent.
// Samples arrive in time order from one device; a corrupted or out-of-order one is dropped and
// counted (the prediction over its place interpolates its neighbours, as over any short gap).

#include <cstddef>
#include <deque>
#include <vector>

#include "liod/error_state.hpp"
#include "liod/imu_trajectory.hpp"
#include "liod/types.hpp"

namespace liod {

struct TimeSpan {
  double from = 0.0;
  double to = 0.0;
};

class ImuBuffer {
 public:
  /// Keeps at most history_s back from the newest sample; a sample whose angular rate or specific
  /// force exceeds the IMU's measurement range on any axis is no measurement.
  ImuBuffer(double history_s, double gyro_range_rad_s, double accel_range_m_s2)
      : history_s_(history_s), gyro_range_(gyro_range_rad_s), accel_range_(accel_range_m_s2) {}

  /// Adds a sample; drops (and counts) a non-finite one, one beyond the measurement range, and
  /// one not after the newest.
  void add(const ImuSample& sample);
  /// Forgets the samples no scan after `time` needs (one is kept before it, for interpolation).
  void forget_before(double time);

  bool empty() const { return samples_.empty(); }
  std::size_t size() const { return samples_.size(); }
  /// Latest sample time, or -inf before any sample.
  double latest_time() const;
  std::size_t dropped() const { return dropped_; }
  const std::deque<ImuSample>& samples() const { return samples_; }

  /// Where the IMU is silent within [from, to]: between consecutive samples more than max_gap
  /// apart, before the first sample when it begins more than max_gap after `from`, and after the
  /// last sample when it ends more than max_gap before `to`; all of it without a sample.
  std::vector<TimeSpan> gaps(double from, double to, double max_gap) const;

 private:
  double history_s_;
  double gyro_range_;
  double accel_range_;
  std::deque<ImuSample> samples_;
  std::size_t dropped_ = 0;
};

/// Nothing was measured over an IMU gap. Holding the last sample there (one sample's vibration,
/// and the turn rate from before the gap, for seconds) smears the deskew and biases the
/// prediction, so the intervals in a gap carry the last estimated twist instead: constant body
/// velocity and angular rate, as an IMU would have measured them. Prediction and deskew use it alike.
void bridge_imu_gaps(std::vector<ImuInterval>& intervals, const std::vector<TimeSpan>& gaps, const NavState& start,
                     const Eigen::Vector3d& angular_rate, const Eigen::Vector3d& gravity);

/// Even so the motion over a gap is a guess: the prior is widened by what a road vehicle may do
/// meanwhile (imu_buffer.cpp's rates), and the LiDAR decides.
void widen_for_imu_gaps(StateCovariance& covariance, const std::vector<TimeSpan>& gaps);

}  // namespace liod
