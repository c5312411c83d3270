#pragma once
// The filter's error state: 17 dimensions [dtheta (right perturbation of R), dp, dv, dbg, dba, dg],
// where dg is the gravity direction's 2-dim perturbation on the sphere (its magnitude is known).
// The world is the first pose's frame, levelled by the start-up alignment, which takes the
// accelerometer bias for tilt; estimating gravity in it (FAST-LIO2's S2 state) lets a change of
// heading correct that tilt instead of bending the accelerometer bias to it.

#include <Eigen/Core>

#include "liod/imu_preintegration.hpp"

namespace liod {

constexpr int kStateDim = 17;
constexpr int kGravityIndex = 15;  // first of the two gravity-direction dimensions
using StateVector = Eigen::Matrix<double, kStateDim, 1>;
using StateCovariance = Eigen::Matrix<double, kStateDim, kStateDim>;

/// Two unit vectors across the gravity direction: its perturbation dg moves it by Exp(B dg).
Eigen::Matrix<double, 3, 2> gravity_tangent_basis(const Eigen::Vector3d& gravity);

/// x (+) delta, with the rotation perturbed on the right.
NavState boxplus(const NavState& x, const StateVector& delta);
/// The error state taking b to a: a = b (+) (a (-) b).
StateVector boxminus(const NavState& a, const NavState& b);

/// The error-state transition of ImuPreintegration::predict(start, start.gravity) over the
/// preintegrated interval, biases and gravity held constant: d(predicted (-) predicted_hat) / d(start error).
StateCovariance imu_transition(const ImuPreintegration& preintegration, const NavState& start);

}  // namespace liod
