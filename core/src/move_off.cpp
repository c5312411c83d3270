#include "liod/move_off.hpp"

#include "liod/bias_holds.hpp"

namespace liod {

void MoveOff::begin(bool standstill, const Eigen::Vector3d& position) {
  active_ = standstill && config_.enabled;
  standstill_position_ = position;
}

void MoveOff::restrict(UpdateParams& params, StateCovariance& predicted_covariance, bool body_rocking) const {
  if (!active_) return;
  params.planes_blind_along_body = config_.forward_axis;
  params.ground_blind_too = body_rocking;
  hold_yaw_rate_bias(predicted_covariance, config_.up_axis);
}

void MoveOff::update(const Eigen::Vector3d& position, std::size_t keyframes) {
  if (active_ && keyframes >= 2 && (position - standstill_position_).norm() >= config_.distance_m) active_ = false;
}

}  // namespace liod
