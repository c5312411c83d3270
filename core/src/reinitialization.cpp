#include "liod/reinitialization.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>

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

NavState placed_at(const NavState& state, const NavState& anchor, const Eigen::Vector3d& forward_body) {
  auto heading = [&](const Eigen::Matrix3d& r) {
    const Eigen::Vector3d f = r * forward_body;
    return std::atan2(f.y(), f.x());
  };
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(heading(anchor.rotation) - heading(state.rotation), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  NavState placed = state;
  placed.rotation = turn * state.rotation;
  placed.velocity = turn * state.velocity;
  placed.position = anchor.position;
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

std::optional<NavState> Reinitialization::take_anchor() {
  if (!anchor_pending_) return std::nullopt;
  anchor_pending_ = false;
  return last_plausible_;
}

}  // namespace liod
