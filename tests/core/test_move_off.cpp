#include "liod/move_off.hpp"

#include <gtest/gtest.h>

#include <random>

namespace liod {
namespace {

StateCovariance random_covariance() {
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 0.1);
  StateCovariance a;
  for (int i = 0; i < kStateDim; ++i) {
    for (int j = 0; j < kStateDim; ++j) a(i, j) = n(rng);
  }
  return a * a.transpose() + 0.01 * StateCovariance::Identity();
}

TEST(MoveOff, ActiveOnlyAfterAStandstillStartWhenEnabled) {
  MoveOff move_off(MoveOffConfig{});
  EXPECT_FALSE(move_off.active()) << "before the start is decided";
  move_off.begin(false, Eigen::Vector3d::Zero());
  EXPECT_FALSE(move_off.active()) << "a rolling start";
  move_off.begin(true, Eigen::Vector3d::Zero());
  EXPECT_TRUE(move_off.active());

  MoveOffConfig disabled;
  disabled.enabled = false;
  MoveOff off(disabled);
  off.begin(true, Eigen::Vector3d::Zero());
  EXPECT_FALSE(off.active());
}

// While active the update's planes are blind along the (configured) forward axis, the ground too
// only while the body rocks, and the gyro bias about the (configured) up axis loses every
// correlation with the rest of the state (the heading's corrections cannot reach it) with its own
// variance kept.
TEST(MoveOff, RestrictBlindsThePlanesAlongTheTrackAndHoldsTheYawRateBias) {
  MoveOffConfig config;
  config.forward_axis = Eigen::Vector3d(0.0, 1.0, 0.0);
  config.up_axis = Eigen::Vector3d(0.0, 0.1, 1.0);
  MoveOff move_off(config);
  move_off.begin(true, Eigen::Vector3d::Zero());
  const StateCovariance prior = random_covariance();

  for (const bool rocking : {false, true}) {
    UpdateParams params;
    StateCovariance p = prior;
    move_off.restrict(params, p, rocking);
    ASSERT_TRUE(params.planes_blind_along_body.has_value());
    EXPECT_EQ(*params.planes_blind_along_body, config.forward_axis);
    EXPECT_EQ(params.ground_blind_too, rocking);
    StateVector yaw_bias = StateVector::Zero();
    yaw_bias.segment<3>(9) = config.up_axis.normalized();
    for (int i = 0; i < kStateDim; ++i) {
      if (i >= 9 && i < 12) continue;
      EXPECT_NEAR(p.row(i).dot(yaw_bias), 0.0, 1e-12) << "state " << i;
    }
    EXPECT_NEAR(yaw_bias.dot(p * yaw_bias), yaw_bias.dot(prior * yaw_bias), 1e-12);
    EXPECT_GT((p - prior).norm(), 1e-3);
  }
}

TEST(MoveOff, RestrictDoesNothingWhenInactive) {
  MoveOff move_off(MoveOffConfig{});
  move_off.begin(false, Eigen::Vector3d::Zero());
  UpdateParams params;
  StateCovariance p = random_covariance();
  const StateCovariance prior = p;
  move_off.restrict(params, p, true);
  EXPECT_FALSE(params.planes_blind_along_body.has_value());
  EXPECT_FALSE(params.ground_blind_too);
  EXPECT_EQ(p, prior);
}

// Stood at (100, 50, 2); ends once 10 m from there with two keyframes in the window, not before
// either, and a standstill start begins it again.
TEST(MoveOff, EndsAfterTheDistanceWithTwoKeyframesAndNotBefore) {
  MoveOff move_off(MoveOffConfig{});
  const Eigen::Vector3d stood(100.0, 50.0, 2.0);
  move_off.begin(true, stood);
  move_off.update(stood + Eigen::Vector3d(7.0, 7.0, 0.0), 2);  // 9.9 m
  EXPECT_TRUE(move_off.active()) << "not far enough";
  move_off.update(stood + Eigen::Vector3d(30.0, 0.0, 0.0), 1);
  EXPECT_TRUE(move_off.active()) << "one keyframe: the standstill's map still is the whole map";
  move_off.update(stood + Eigen::Vector3d(6.0, 8.0, 0.0), 2);  // 10 m
  EXPECT_FALSE(move_off.active());
  move_off.update(stood, 5);
  EXPECT_FALSE(move_off.active()) << "back where it stood: it stays ended";

  move_off.begin(true, Eigen::Vector3d(0.0, 0.0, 0.0));
  EXPECT_TRUE(move_off.active());
  move_off.update(stood, 2);  // 111 m from the new standstill
  EXPECT_FALSE(move_off.active());
}

}  // namespace
}  // namespace liod
