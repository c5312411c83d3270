#pragma once
// What the LiDAR update may not teach the IMU states, and when.
//
// A degenerate stretch (a highway between long rails, a tunnel, the first metres from a
// standstill) leaves the position along the track to the ground's and the rails' weak pull, which
// drags each scan towards earlier keyframes. With nothing to tell the two apart the filter takes
// that pull as a forward accelerometer bias (and as a gravity tilt, which reads as the same
// acceleration), and the speed decays. So after a scan that left the along-track position
// unconstrained, the next update keeps the forward bias and the tilt at their prior (the forward
// hold): the velocity takes the corrections meanwhile. A turn separates the two (the bias lives in
// the body, the tilt in the world), so a turn releases the hold; a scan well above the degeneracy
// threshold does too.
//
// An IMU that contradicts the LiDAR far beyond its own covariance (a clock step, a sensor gone
// wrong) must not teach the biases and gravity either: they would carry its error on into the
// degenerate stretches where nothing corrects them. The scan's pose then comes from the LiDAR.

#include <Eigen/Core>
#include <cstddef>

#include "liod/error_state.hpp"
#include "liod/held_bias_trim.hpp"

namespace liod {

struct BiasHoldConfig {
  Eigen::Vector3d forward_axis = Eigen::Vector3d::UnitX();  // body frame
  Eigen::Vector3d up_axis = Eigen::Vector3d::UnitZ();
  /// LiDAR information (weighted residual count) along the weakest translation below which a
  /// scan is degenerate and the forward bias is held for the next.
  double degeneracy_eigenvalue = 30.0;
  /// A held bias is released only by a scan with this many times degeneracy_eigenvalue along its
  /// weakest direction (hysteresis: under a gantry the information swings about the threshold
  /// scan by scan, and each scan just above would let its along-track pull into the bias).
  double release_eigenvalue_factor = 2.0;
  /// A turn faster than this (deg/s, by the IMU and by the update alike) releases the hold; 0: never.
  double release_yaw_rate_deg_s = 5.0;
  /// Squared Mahalanobis distance (6 pose dof) of the update from the IMU prediction beyond which
  /// the IMU contradicts the LiDAR. chi-square(6) exceeds 40 with probability 3e-7.
  double max_prediction_nis = 200.0;
  /// Scans the IMU must have agreed with the LiDAR before a turn may release the hold: an IMU
  /// whose clock stepped turns where the vehicle does not.
  int consistent_scans_to_release = 50;
  double trim_window_s = 20.0;  // held_bias_trim.hpp
  double trim_gain = 0.5;
};

/// The forward accelerometer bias and the gravity tilt along the track keep their prior: cut from
/// the rest of the state's update (held together: at a standstill the filter knows their sum, the
/// specific force, far better than either).
void hold_forward_acceleration(StateCovariance& p, const NavState& x, const Eigen::Vector3d& forward_body);
/// The gyro's bias about the vehicle's up axis keeps its prior: cut from the heading's update.
void hold_yaw_rate_bias(StateCovariance& p, const Eigen::Vector3d& up_body);
/// The biases and gravity keep their prior: cut from the pose, velocity and each other's updates.
void hold_imu_states(StateCovariance& p);
/// Whether the IMU prediction and the update both turned the body about the vertical faster than
/// yaw_rate_deg_s over the scan (0: never). The update alone would count the LiDAR's corrections
/// at a static start as turns; the IMU alone, one whose clock is off, turning where the vehicle
/// does not.
bool turning_faster_than(const NavState& start, const NavState& predicted, const NavState& updated, double duration,
                         double yaw_rate_deg_s);
/// How far the update moved the pose from the IMU prediction, in the prediction's own covariance
/// (squared Mahalanobis distance over the 6 pose dimensions).
double prediction_nis(const NavState& updated, const NavState& predicted, const StateCovariance& predicted_covariance);

class BiasHolds {
 public:
  explicit BiasHolds(const BiasHoldConfig& config);

  bool forward_held() const { return forward_held_; }
  void hold_forward(bool held) { forward_held_ = held; }
  /// Before this scan's update: the forward hold applied to the predicted covariance.
  void apply(StateCovariance& predicted_covariance, const NavState& predicted) const;
  /// After the update: whether it contradicts the IMU's prediction (counted).
  bool imu_contradicts(const NavState& updated, const NavState& predicted, const StateCovariance& predicted_covariance);
  /// Whether an update agrees with a prediction (not counted).
  bool consistent(const NavState& updated, const NavState& predicted, const StateCovariance& predicted_covariance) const;
  /// The next scan's forward hold, from this scan's weakest translation information and turn.
  void decide_next(double min_translation_eigenvalue, bool turning);
  /// A held scan's forward velocity correction (m/s, body frame) over its duration: the held
  /// bias trimmed by what the corrections say of it (held_bias_trim.hpp). `held`: this scan's hold.
  void trim(bool held, double forward_velocity_correction, double duration, NavState& state);
  std::size_t inconsistent_scans() const { return inconsistent_scans_; }

 private:
  BiasHoldConfig config_;
  bool forward_held_ = false;
  HeldBiasTrim trim_;
  int scans_since_inconsistent_ = 0;
  std::size_t inconsistent_scans_ = 0;
};

}  // namespace liod
