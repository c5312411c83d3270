#include "liod/reinitialization.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "liod/so3.hpp"

namespace liod {

bool beyond_registration_basin(const StateCovariance& relative, const ReinitializationConfig& config) {
  const Eigen::Matrix3d position = relative.block<3, 3>(3, 3);
  if (!position.allFinite()) return true;
  const double worst_variance = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(position, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
  const double reach = config.basin_sigmas * std::sqrt(std::max(worst_variance, 0.0));
  return reach > config.registration_basin_m;
}

StateCovariance relative_prediction_covariance(const StateCovariance& predicted, const StateCovariance& transition,
                                               const StateCovariance& start) {
  // predicted = F P F^T + Q (+ the IMU gaps' widening); the start's position rows and columns of P
  // carried through F are taken out again.
  StateCovariance position_part = StateCovariance::Zero();
  position_part.block<3, kStateDim>(3, 0) = start.block<3, kStateDim>(3, 0);
  position_part.block<kStateDim, 3>(0, 3) = start.block<kStateDim, 3>(0, 3);
  return predicted - transition * position_part * transition.transpose();
}

Eigen::Matrix3d restart_covariance(StateCovariance& p) {
  const Eigen::Matrix3d dead_reckoned = p.block<3, 3>(3, 3);
  // The start-up's origin prior (start_up.cpp): the position defines the map. Left at the dead
  // reckoning's metres, it would take every scan's position correction on the new map for its
  // own, and the velocity, which the next scans are to measure, would learn nothing from them.
  p.block<3, kStateDim>(3, 0).setZero();
  p.block<kStateDim, 3>(0, 3).setZero();
  p.block<3, 3>(3, 3) = Eigen::Matrix3d::Identity() * 1e-6;
  return dead_reckoned;
}

NavState placed_at(const NavState& state, const NavState& anchor, const std::deque<ImuSample>& samples) {
  Eigen::Matrix3d rotation = anchor.rotation;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    const double from = std::max(samples[i - 1].time, anchor.time);
    const double to = std::min(samples[i].time, state.time);
    if (to <= from) continue;
    const Eigen::Vector3d rate = 0.5 * (samples[i - 1].gyro + samples[i].gyro) - anchor.gyro_bias;
    rotation = rotation * so3::exp(rate * (to - from));
  }
  NavState placed = state;
  placed.rotation = so3::normalize(rotation);
  placed.velocity = placed.rotation * (state.rotation.transpose() * state.velocity);
  placed.position = anchor.position;
  placed.gravity = anchor.gravity;
  placed.gyro_bias = anchor.gyro_bias;
  placed.accel_bias = anchor.accel_bias;
  return placed;
}

void Reinitialization::begin_new_map(StateCovariance& covariance) {
  frame_position_covariance_ += restart_covariance(covariance);
  recovering_ = true;
  trusted_before_ = false;
  ++new_maps_;
}

bool Reinitialization::converged(bool map_trusted, bool registered, bool constrained) {
  if (recovering_ && trusted_before_ && registered && constrained) recovering_ = false;
  trusted_before_ = map_trusted;
  return !recovering_;
}

bool Reinitialization::check(const NavState& state, const StateCovariance& covariance) {
  StateFault fault = check_state(state, config_.limits);
  if (fault == StateFault::kNone) fault = check_covariance(covariance);
  if (fault == StateFault::kNone) {
    last_plausible_ = state;
    return true;
  }
  anchor_pending_ = true;
  recovering_ = false;
  ++restarts_;
  return false;
}


}  // namespace liod
