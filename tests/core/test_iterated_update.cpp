#include <gtest/gtest.h>

#include <random>

#include "liod/iterated_update.hpp"
#include "liod/so3.hpp"

namespace {

// Points on the faces of a street-like scene: ground, two facades and a cross wall.
std::vector<Eigen::Vector3d> scene(bool with_cross_wall, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 4000; ++i) {
    const double a = u(rng);
    const double b = u(rng);
    switch (i % (with_cross_wall ? 5 : 4)) {
      case 0: pts.emplace_back(30 * a, 8 * b, -1.5); break;       // ground
      case 1: pts.emplace_back(30 * a, -8.0, 4 + 5 * b); break;   // right facade
      case 2: pts.emplace_back(30 * a, 8.0, 4 + 5 * b); break;    // left facade
      case 3: pts.emplace_back(30 * a, 8 * b, 10.0); break;       // roof (tunnel ceiling)
      default: pts.emplace_back(20.0, 8 * a, 4 + 5 * b); break;   // wall across the street
    }
  }
  return pts;
}

struct SceneSetup {
  liod::LocalMap map{1.0, 50, 0.1};
  liod::LocalMap edges{1.0, 50, 0.1};
  std::vector<Eigen::Vector3d> body;
  liod::NavState truth;
};

SceneSetup make_setup(bool cross_wall) {
  SceneSetup s;
  s.map.add(scene(cross_wall, 1), 0);
  s.truth.rotation = liod::so3::exp(Eigen::Vector3d(0.01, -0.02, 0.3));
  s.truth.position = Eigen::Vector3d(2.0, 0.5, 0.1);
  for (const auto& p : scene(cross_wall, 2)) {
    if (std::abs(p.x()) < 25.0) s.body.push_back(s.truth.rotation.transpose() * (p - s.truth.position));
  }
  return s;
}

TEST(IteratedUpdate, RecoversAPoseFromAnOffsetPrior) {
  SceneSetup s = make_setup(true);
  liod::NavState prior = s.truth;
  prior.position += Eigen::Vector3d(0.3, -0.2, 0.1);
  prior.rotation = prior.rotation * liod::so3::exp(Eigen::Vector3d(0.0, 0.01, 0.03));
  liod::StateCovariance cov = liod::StateCovariance::Identity() * 1e-4;
  cov.topLeftCorner<6, 6>() = Eigen::Matrix<double, 6, 6>::Identity();
  liod::UpdateParams params;
  params.max_iterations = 10;
  const auto result = liod::iterated_update(prior, cov, s.body, s.map, {}, s.edges, params);
  EXPECT_LT((result.state.position - s.truth.position).norm(), 0.01);
  EXPECT_LT(liod::so3::log(result.state.rotation.transpose() * s.truth.rotation).norm(), 1e-3);
  EXPECT_GT(result.residuals, 1000);
  EXPECT_GT(result.min_translation_eigenvalue, 100.0);
  EXPECT_EQ(result.degenerate_directions, 0);
  // The posterior is more certain about the pose than the prior.
  EXPECT_LT(result.covariance(3, 3), 1e-3);
}

TEST(IteratedUpdate, TunnelIsFlaggedAndTheAxisFollowsThePrior) {
  SceneSetup s = make_setup(false);
  liod::NavState prior = s.truth;
  prior.position += Eigen::Vector3d(0.4, 0.1, 0.0);  // along the tunnel axis the LiDAR sees nothing
  liod::StateCovariance cov = liod::StateCovariance::Identity() * 1e-4;
  cov.topLeftCorner<6, 6>() = Eigen::Matrix<double, 6, 6>::Identity() * 0.25;
  liod::UpdateParams params;
  const auto result = liod::iterated_update(prior, cov, s.body, s.map, {}, s.edges, params);
  EXPECT_LT(result.min_translation_eigenvalue, 1.0);
  EXPECT_EQ(result.degenerate_directions, 1);
  // Across the tunnel the scan fixes the pose; the world x axis stays where the prior put it.
  const Eigen::Vector3d error = result.state.position - s.truth.position;
  EXPECT_NEAR(error.x(), 0.4, 0.02);
  EXPECT_LT(std::abs(error.y()), 0.02);
  EXPECT_LT(std::abs(error.z()), 0.02);
}

// A car driving at 15 m/s whose attitude prior is pitched 1 deg nose up while its velocity is
// known well (what the gravity leak into the forward axis leaves when the scene cannot show the
// tilt): the vertical velocity constraint brings the forward axis back onto the direction of travel.
TEST(IteratedUpdate, VerticalVelocityConstraintTiesThePitchToTheTravelDirection) {
  liod::NavState truth;
  truth.rotation = liod::so3::exp(Eigen::Vector3d(0.01, -0.02, 0.3));
  truth.velocity = truth.rotation * Eigen::Vector3d(15.0, 0.0, 0.0);
  liod::NavState prior = truth;
  prior.rotation = truth.rotation * liod::so3::exp(Eigen::Vector3d(0.0, -1.0 * M_PI / 180.0, 0.0));
  liod::StateCovariance cov = liod::StateCovariance::Identity() * 1e-6;
  cov.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * std::pow(2.0 * M_PI / 180.0, 2);
  cov.block<3, 3>(6, 6) = Eigen::Matrix3d::Identity() * 1e-4;  // 0.01 m/s
  liod::UpdateParams params;
  params.max_iterations = 10;
  const auto pitch_of = [&](const liod::NavState& x) {
    return liod::so3::log(truth.rotation.transpose() * x.rotation).y() * 180.0 / M_PI;
  };
  // No LiDAR residuals: only the prior and, when on, the constraint.
  liod::LocalMap empty{1.0, 50, 0.1};
  const auto off = liod::iterated_update(prior, cov, {}, empty, {}, empty, params);
  EXPECT_NEAR(pitch_of(off.state), -1.0, 1e-6);
  params.vertical_velocity_std = 0.05;
  const auto on = liod::iterated_update(prior, cov, {}, empty, {}, empty, params);
  EXPECT_NEAR(pitch_of(on.state), 0.0, 0.1);
  EXPECT_NEAR((on.state.velocity - truth.velocity).norm(), 0.0, 0.05);
  // The posterior pitch is known to about the constraint's 0.05 m/s over 15 m/s (0.19 deg).
  EXPECT_LT(std::sqrt(on.covariance(1, 1)) * 180.0 / M_PI, 0.3);
  // An up axis tilted with the body (the IMU mounted nose up by 1 deg) keeps the prior's pitch.
  params.vertical_axis = Eigen::Vector3d(std::sin(1.0 * M_PI / 180.0), 0.0, std::cos(1.0 * M_PI / 180.0));
  const auto mounted = liod::iterated_update(prior, cov, {}, empty, {}, empty, params);
  EXPECT_NEAR(pitch_of(mounted.state), -1.0, 0.1);
}

}  // namespace
