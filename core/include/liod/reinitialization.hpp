#pragma once
// Re-initialisation: when the odometry's state can no longer be registered on its local map, or
// can no longer be true at all, it starts again instead of carrying on from there.
//
// A LiDAR outage (a sensor rebooting, ~30 s for an RS-Helios) leaves the IMU to carry the state.
// Dead reckoning drifts with the accelerometer bias's uncertainty times t^2/2 and its random walk
// times t^2.5, and the first scan back would register against the map left behind from a pose
// metres off: where the map's planes are nearer than the correspondence gate to the wrong ones,
// the update locks onto those. So the scan's predicted position covariance is held against the
// map's registration basin: a scan lands in the basin while the gate (map neighbours farther than
// it are not used, map_correspondence.hpp) holds basin_sigmas standard deviations of its position
// along the least certain direction. Beyond it the map left behind is dropped and a new one
// starts from the dead-reckoned pose: the IMU's attitude (its gyro drifts a few tenths of a
// degree in 30 s), its velocity with the covariance the prediction gives it, and a position that
// defines the new map, so that the published pose stays continuous with the dead reckoning. The
// scans are reported initializing until the registration on the new map has converged: the
// velocity known well enough to deskew (the map then starts once more from a scan deskewed with
// it, as after a rolling start) and a scan registered on that map with every direction constrained.
//
// A state that fails the sanity checks (state_sanity.hpp) starts the odometry from its start-up
// again (speed search), placed at the last plausible pose: its attitude carried on by the gyro,
// its gravity and biases (placed_at).

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>

#include "liod/error_state.hpp"
#include "liod/state_sanity.hpp"
#include "liod/types.hpp"

namespace liod {

struct ReinitializationConfig {
  /// How far a predicted scan may be off and still find its own correspondences: the front end's
  /// correspondence gate (odometry.correspondence_gate_m).
  double registration_basin_m = 1.0;
  /// The basin must hold this many standard deviations of the predicted position (3: a Gaussian
  /// error is beyond it along that direction with probability 0.3 %).
  double basin_sigmas = 3.0;
  /// What a plausible state is (the daemon's pose_socket.* limits).
  StateLimits limits;
};

/// Whether a scan predicted with this covariance lies outside the map's registration basin.
/// `relative`: the prediction's covariance of the scan's pose relative to the state it was
/// predicted from (relative_prediction_covariance).
bool beyond_registration_basin(const StateCovariance& relative, const ReinitializationConfig& config);

/// The predicted covariance without the start state's own position uncertainty: how far the scan
/// may be from where the prediction puts it relative to the map, which was registered with that
/// state. A stretch where the map leaves a direction unconstrained (a tunnel) grows the absolute
/// position covariance, not this. `transition`: the prediction's error-state transition
/// (imu_transition), `start`: the covariance it was propagated from.
StateCovariance relative_prediction_covariance(const StateCovariance& predicted, const StateCovariance& transition,
                                               const StateCovariance& start);

/// The covariance a new local map starts from at a dead-reckoned state: the attitude, velocity,
/// biases and gravity as predicted; the position defines the new map (as the start-up's does),
/// cut from the rest. The dead reckoning's own position uncertainty is returned: where the new
/// map lies in the old one's frame.
Eigen::Matrix3d restart_covariance(StateCovariance& covariance);

/// A start-up's state (levelled from the accelerometer, at the origin, heading as the alignment
/// left it) placed where the odometry was: the anchor's attitude carried on by the gyro `samples`
/// to the state's time, the anchor's position, gravity and biases (they passed the checks), and
/// the start-up's velocity in the body. Levelling under way tilts by the acceleration over g (2 deg
/// at 0.4 m/s^2), and the vertical velocity constraint takes seconds to undo that; the gyro keeps
/// the anchor's attitude to a small fraction of it over the start-up's second.
NavState placed_at(const NavState& state, const NavState& anchor, const std::deque<ImuSample>& samples);

class Reinitialization {
 public:
  explicit Reinitialization(const ReinitializationConfig& config) : config_(config) {}

  /// A scan predicted with this relative covariance must start a new map. Not while recovering:
  /// the map is then the new one, started a scan or a few before, and a velocity as uncertain as
  /// the dead reckoning leaves it is what the next registrations measure (as after a rolling
  /// start); another new map would be no nearer.
  bool beyond_basin(const StateCovariance& relative) const {
    return !recovering_ && beyond_registration_basin(relative, config_);
  }
  /// A new map started from a dead-reckoned state (see restart_covariance); its scans recover.
  void begin_new_map(StateCovariance& covariance);
  bool recovering() const { return recovering_; }
  /// After a recovering scan: whether its registration converged (the map trusted before the
  /// scan, and the scan registered on it with every direction constrained); the recovery ends
  /// with it. `map_trusted`: after the scan (the scan that makes it trusted registered on the
  /// map deskewed with the dead-reckoned velocity).
  bool converged(bool map_trusted, bool registered, bool constrained);

  /// After a scan: whether its state is plausible. A plausible one is kept as the anchor of a
  /// restart; an implausible one sets the anchor pending for the start-up to take.
  bool check(const NavState& state, const StateCovariance& covariance);
  /// The last plausible state while a start-up that follows an implausible one has not begun.
  std::optional<NavState> anchor() const { return anchor_pending_ ? last_plausible_ : std::nullopt; }
  /// That start-up has begun from the anchor.
  void resumed() { anchor_pending_ = false; }

  /// Where the current map lies in the frame of the first: the position covariance the new maps
  /// added (the dead reckoning's), for the published covariance.
  const Eigen::Matrix3d& frame_position_covariance() const { return frame_position_covariance_; }
  std::size_t new_maps() const { return new_maps_; }
  std::size_t restarts() const { return restarts_; }

 private:
  ReinitializationConfig config_;
  bool recovering_ = false;
  bool trusted_before_ = false;
  std::optional<NavState> last_plausible_;
  bool anchor_pending_ = false;
  Eigen::Matrix3d frame_position_covariance_ = Eigen::Matrix3d::Zero();
  std::size_t new_maps_ = 0;
  std::size_t restarts_ = 0;
};

}  // namespace liod
