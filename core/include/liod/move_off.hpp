#pragma once
// Moving off from a standstill start. The map is then the standstill's one keyframe, seen from one
// viewpoint: its planes (rail ends, a ring's short arcs on posts and on objects ahead, the ground's
// rings) pull each moving-off scan back towards where the car stood, and a scan that outweighs the
// IMU loses speed. Until the car has left that map behind (two keyframes and a distance), walls
// locate the scan across the track only, and the ground too once the body rolls (at rest the scans
// are the map's viewpoint and the ground's fine pattern holds the position); edges and posts keep
// their full pull. The same keyframe turns the heading too, so the gyro's bias about the vertical,
// measured at rest (start_up.hpp), is not taught by the LiDAR meanwhile.

#include <Eigen/Core>
#include <cstddef>

#include "liod/error_state.hpp"
#include "liod/iterated_update.hpp"

namespace liod {

struct MoveOffConfig {
  bool enabled = true;
  /// Ends this far from where the car stood (with two keyframes): nearer, the ground voxels beyond
  /// 10 m hold one ring's arc each (rings lie 1-5 m apart on the road at 10-20 m), which pulls
  /// back too, and in a tunnel of constant section nothing else locates the car along it.
  double distance_m = 10.0;
  Eigen::Vector3d forward_axis = Eigen::Vector3d::UnitX();  // body frame
  Eigen::Vector3d up_axis = Eigen::Vector3d::UnitZ();
};

class MoveOff {
 public:
  explicit MoveOff(const MoveOffConfig& config) : config_(config) {}

  /// The start decided: a standstill at `position`, or not.
  void begin(bool standstill, const Eigen::Vector3d& position);
  bool active() const { return active_; }
  /// While active: the update's planes blind along the track (and the ground too while the body
  /// rocks), the yaw-rate bias held in the predicted covariance.
  void restrict(UpdateParams& params, StateCovariance& predicted_covariance, bool body_rocking) const;
  /// Ends once the car is distance_m from where it stood with two keyframes in the window.
  void update(const Eigen::Vector3d& position, std::size_t keyframes);

 private:
  MoveOffConfig config_;
  bool active_ = false;
  Eigen::Vector3d standstill_position_ = Eigen::Vector3d::Zero();
};

}  // namespace liod
