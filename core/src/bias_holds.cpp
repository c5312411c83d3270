#include "liod/bias_holds.hpp"

#include <algorithm>
#include <cmath>

#include "liod/angles.hpp"
#include "liod/so3.hpp"

namespace liod {
namespace {

// Zeroes the cross-covariance between the error-state subspace spanned by the orthonormal
// columns of u and the rest of the state: pose residuals then cannot move those components, and
// their covariance among themselves stays as it was (as do the state's other covariances).
template <int kColumns>
void decouple_subspace(StateCovariance& p, const Eigen::Matrix<double, kStateDim, kColumns>& u) {
  const StateCovariance inside = u * u.transpose();
  const StateCovariance across = StateCovariance::Identity() - inside;
  p = across * p * across + inside * p * inside;
}

}  // namespace

void hold_forward_acceleration(StateCovariance& p, const NavState& x, const Eigen::Vector3d& forward_body) {
  Eigen::Matrix<double, kStateDim, 2> u = Eigen::Matrix<double, kStateDim, 2>::Zero();
  u.block<3, 1>(12, 0) = forward_body.normalized();
  // Gravity moved by B dg changes the acceleration by (B dg) x g, along the track by
  // dg . B^T (g x forward).
  const Eigen::Vector2d along = gravity_tangent_basis(x.gravity).transpose() * x.gravity.cross(x.rotation * forward_body);
  if (along.norm() < 1e-9) {
    decouple_subspace<1>(p, u.leftCols<1>());
    return;
  }
  u.block<2, 1>(kGravityIndex, 1) = along.normalized();
  decouple_subspace<2>(p, u);
}

void hold_yaw_rate_bias(StateCovariance& p, const Eigen::Vector3d& up_body) {
  Eigen::Matrix<double, kStateDim, 1> u = Eigen::Matrix<double, kStateDim, 1>::Zero();
  u.segment<3>(9) = up_body.normalized();
  decouple_subspace<1>(p, u);
}

void hold_imu_states(StateCovariance& p) {
  Eigen::Matrix<double, kStateDim, kStateDim - 9> u = Eigen::Matrix<double, kStateDim, kStateDim - 9>::Zero();
  u.bottomRows<kStateDim - 9>().setIdentity();
  decouple_subspace<kStateDim - 9>(p, u);
}

bool turning_faster_than(const NavState& start, const NavState& predicted, const NavState& updated, double duration,
                         double yaw_rate_deg_s) {
  if (yaw_rate_deg_s <= 0.0 || duration <= 0.0) return false;
  const Eigen::Vector3d up = start.gravity.normalized();
  const double threshold = yaw_rate_deg_s * kDegToRad;
  return std::abs(so3::turn_rate_about(start.rotation, predicted.rotation, up, duration)) > threshold &&
         std::abs(so3::turn_rate_about(start.rotation, updated.rotation, up, duration)) > threshold;
}

double prediction_nis(const NavState& updated, const NavState& predicted, const StateCovariance& predicted_covariance) {
  const Eigen::Matrix<double, 6, 1> pose = boxminus(updated, predicted).head<6>();
  return pose.dot(predicted_covariance.topLeftCorner<6, 6>().ldlt().solve(pose));
}

BiasHolds::BiasHolds(const BiasHoldConfig& config) : config_(config), trim_(config.trim_window_s, config.trim_gain) {}

void BiasHolds::apply(StateCovariance& predicted_covariance, const NavState& predicted) const {
  if (forward_held_) hold_forward_acceleration(predicted_covariance, predicted, config_.forward_axis);
}

bool BiasHolds::imu_contradicts(const NavState& updated, const NavState& predicted,
                                const StateCovariance& predicted_covariance) {
  scans_since_inconsistent_ = std::min(scans_since_inconsistent_ + 1, config_.consistent_scans_to_release);
  // A NaN distance (a state gone non-finite) contradicts as surely as a large one.
  if (consistent(updated, predicted, predicted_covariance)) return false;
  ++inconsistent_scans_;
  scans_since_inconsistent_ = 0;
  return true;
}

bool BiasHolds::consistent(const NavState& updated, const NavState& predicted,
                           const StateCovariance& predicted_covariance) const {
  return prediction_nis(updated, predicted, predicted_covariance) <= config_.max_prediction_nis;
}

void BiasHolds::decide_next(double min_translation_eigenvalue, bool turning) {
  const double threshold = config_.degeneracy_eigenvalue * (forward_held_ ? config_.release_eigenvalue_factor : 1.0);
  const bool consistent = scans_since_inconsistent_ >= config_.consistent_scans_to_release;
  forward_held_ = min_translation_eigenvalue < threshold && !(turning && consistent);
}

void BiasHolds::trim(bool held, double forward_velocity_correction, double duration, NavState& state) {
  if (!held) {
    trim_.reset();
  } else if (const auto change = trim_.add_held_scan(forward_velocity_correction, duration)) {
    state.accel_bias += config_.forward_axis.normalized() * *change;
  }
}

}  // namespace liod
