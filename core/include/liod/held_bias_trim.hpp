#pragma once
// The forward accelerometer bias, while it is held out of the LiDAR updates (the forward hold,
// bias_holds.hpp), keeps the value it had when the hold began; the velocity takes the
// LiDAR's along-track corrections meanwhile. A held bias that is wrong shows in those corrections:
// the IMU prediction gains or loses speed at the bias's error, and the LiDAR gives it back scan
// after scan (a bias 0.17 m/s^2 wrong, learned at a gantry and held for 30 s, leaves the
// speed 0.9 m/s low by its end: docs/design.md, "Bias holds in degenerate stretches"). The corrections' rate over a long held stretch is that
// error, and a part of it is taken off the bias: slowly, so that one scan's pull, which the hold
// exists to keep out, does not count. The median rate, not the mean, so that the large corrections
// of a rolling start's first scans (the speed found, not an acceleration) do not count either.
#include <optional>
#include <vector>

namespace liod {

class HeldBiasTrim {
 public:
  /// window_s: held time over which the corrections' rate is taken (0: never trims); gain: the
  /// share of that rate taken off the bias at the window's end.
  HeldBiasTrim(double window_s, double gain) : window_s_(window_s), gain_(gain) {}

  /// One held scan: what the LiDAR changed in the IMU-predicted speed along the forward axis (m/s)
  /// over the scan's duration (s). Once window_s of held scans are in, returns the change to add to
  /// the forward accelerometer bias (m/s^2) and starts the next window.
  std::optional<double> add_held_scan(double forward_velocity_correction, double duration);
  /// The hold released: the filter estimates the bias itself, and the window starts anew.
  void reset();

 private:
  double window_s_;
  double gain_;
  double held_s_ = 0.0;
  std::vector<double> rates_;  // m/s^2, one per held scan of the window
};

}  // namespace liod
