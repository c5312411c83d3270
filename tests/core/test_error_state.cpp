#include <gtest/gtest.h>

#include <random>

#include "liod/error_state.hpp"
#include "liod/so3.hpp"

namespace {

// A state far from the identity, with gravity tilted as a start-up alignment leaves it.
liod::NavState tilted_state() {
  liod::NavState x;
  x.rotation = liod::so3::exp(Eigen::Vector3d(0.1, -0.2, 2.5));
  x.position = {12.0, -3.0, 0.5};
  x.velocity = {9.0, 4.0, -0.2};
  x.gyro_bias = {0.004, -0.003, 0.005};
  x.accel_bias = {-0.09, 0.05, -0.07};
  x.gravity = liod::so3::exp(Eigen::Vector3d(0.01, -0.03, 0.0)) * Eigen::Vector3d(0.0, 0.0, -9.80665);
  return x;
}

liod::StateVector random_error(std::mt19937& rng, double scale) {
  std::normal_distribution<double> n(0.0, scale);
  liod::StateVector d;
  for (int i = 0; i < liod::kStateDim; ++i) d(i) = n(rng);
  return d;
}

TEST(ErrorState, GravityTangentBasisIsOrthonormalAndAcrossGravity) {
  const liod::NavState x = tilted_state();
  const Eigen::Matrix<double, 3, 2> b = liod::gravity_tangent_basis(x.gravity);
  EXPECT_NEAR((b.transpose() * b - Eigen::Matrix2d::Identity()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((b.transpose() * x.gravity).norm(), 0.0, 1e-12);
}

TEST(ErrorState, BoxminusUndoesBoxplusIncludingGravity) {
  std::mt19937 rng(7);
  const liod::NavState x = tilted_state();
  for (int trial = 0; trial < 100; ++trial) {
    const liod::StateVector d = random_error(rng, 0.05);
    const liod::NavState y = liod::boxplus(x, d);
    EXPECT_NEAR(y.gravity.norm(), x.gravity.norm(), 1e-9);  // only the direction moves
    EXPECT_NEAR((liod::boxminus(y, x) - d).norm(), 0.0, 1e-9) << "trial " << trial;
  }
  // A gravity perturbation tilts gravity by its norm, about an axis across it.
  liod::StateVector tilt = liod::StateVector::Zero();
  tilt(liod::kGravityIndex) = 0.02;
  const liod::NavState y = liod::boxplus(x, tilt);
  const double angle = std::acos(y.gravity.normalized().dot(x.gravity.normalized()));
  EXPECT_NEAR(angle, 0.02, 1e-9);
}

// The transition must be the derivative of the prediction it stands for: perturb the start state
// along each error dimension, predict, and compare.
TEST(ErrorState, ImuTransitionMatchesTheNumericalDerivativeOfThePrediction) {
  const liod::NavState start = tilted_state();
  liod::ImuPreintegration pre(start.gyro_bias, start.accel_bias, liod::ImuNoise{});
  for (int k = 0; k < 20; ++k) {  // 0.1 s of a turning, accelerating body at 200 Hz
    const double t = k * 0.005;
    pre.integrate(Eigen::Vector3d(0.05, -0.02, 0.4 + t) + start.gyro_bias,
                  Eigen::Vector3d(1.5, 0.8 - t, 9.7) + start.accel_bias, 0.005);
  }
  const liod::StateCovariance f = liod::imu_transition(pre, start);
  const liod::NavState end = pre.predict(start, start.gravity);
  constexpr double kStep = 1e-6;
  for (int i = 0; i < liod::kStateDim; ++i) {
    liod::StateVector d = liod::StateVector::Zero();
    d(i) = kStep;
    const liod::NavState moved = liod::boxplus(start, d);
    const liod::StateVector column = liod::boxminus(pre.predict(moved, moved.gravity), end) / kStep;
    EXPECT_LT((column - f.col(i)).norm(), 1e-4 * std::max(1.0, f.col(i).norm())) << "error dimension " << i
        << "\nnumerical " << column.transpose() << "\nanalytic  " << f.col(i).transpose();
  }
}

}  // namespace
