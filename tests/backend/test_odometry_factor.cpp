// The odometry factor's covariance (odometry_factor.hpp): the first-order propagation of two
// keyframes' pose covariances into their relative pose must match what sampling the two poses
// gives, in the residual convention of PoseGraph (translation, left rotation perturbation).

#include <gtest/gtest.h>

#include <random>

#include "liod/backend/odometry_factor.hpp"
#include "liod/so3.hpp"

namespace {

liod::NavState pose(const Eigen::Vector3d& rotation_vector, const Eigen::Vector3d& position) {
  liod::NavState s;
  s.rotation = liod::so3::exp(rotation_vector);
  s.position = position;
  return s;
}

liod::PoseCovariance random_covariance(std::mt19937& rng, double rotation_sigma, double position_sigma) {
  std::normal_distribution<double> n(0.0, 1.0);
  liod::PoseCovariance a;
  for (int i = 0; i < 36; ++i) a.data()[i] = n(rng);
  liod::PoseCovariance c = a * a.transpose() / 6.0;
  Eigen::Matrix<double, 6, 1> scale;
  scale << Eigen::Vector3d::Constant(rotation_sigma), Eigen::Vector3d::Constant(position_sigma);
  return scale.asDiagonal() * c * scale.asDiagonal();
}

// A pose drawn around `s`: right perturbation of the rotation, world perturbation of the position.
liod::NavState perturbed(const liod::NavState& s, const Eigen::Matrix<double, 6, 1>& delta) {
  liod::NavState out = s;
  out.rotation = s.rotation * liod::so3::exp(delta.head<3>());
  out.position = s.position + delta.tail<3>();
  return out;
}

Eigen::Matrix<double, 6, 1> residual(const liod::NavState& a, const liod::NavState& b, const Eigen::Isometry3d& measured) {
  const Eigen::Matrix3d r_ab = a.rotation.transpose() * b.rotation;
  const Eigen::Vector3d t_ab = a.rotation.transpose() * (b.position - a.position);
  const Eigen::Quaterniond delta = Eigen::Quaterniond(measured.linear()) * Eigen::Quaterniond(r_ab).conjugate();
  Eigen::Matrix<double, 6, 1> r;
  r << t_ab - measured.translation(), 2.0 * delta.vec() * (delta.w() < 0 ? -1.0 : 1.0);
  return r;
}

TEST(OdometryFactor, RelativeCovarianceMatchesSampledPoses) {
  std::mt19937 rng(11);
  const liod::NavState a = pose({0.02, -0.03, 0.8}, {10.0, -4.0, 0.5});
  const liod::NavState b = pose({0.01, 0.02, 0.95}, {12.5, -2.0, 0.6});
  const liod::PoseCovariance pa = random_covariance(rng, 2e-3, 0.01);
  const liod::PoseCovariance pb = random_covariance(rng, 3e-3, 0.02);
  const liod::Matrix6d predicted = liod::relative_pose_covariance(a, pa, b, pb);

  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();
  measured.linear() = a.rotation.transpose() * b.rotation;
  measured.translation() = a.rotation.transpose() * (b.position - a.position);
  const Eigen::LLT<liod::PoseCovariance> la(pa), lb(pb);
  std::normal_distribution<double> n(0.0, 1.0);
  liod::Matrix6d sampled = liod::Matrix6d::Zero();
  constexpr int kSamples = 40000;
  for (int k = 0; k < kSamples; ++k) {
    Eigen::Matrix<double, 6, 1> za, zb;
    for (int i = 0; i < 6; ++i) za[i] = n(rng), zb[i] = n(rng);
    const auto r = residual(perturbed(a, la.matrixL() * za), perturbed(b, lb.matrixL() * zb), measured);
    sampled += r * r.transpose();
  }
  sampled /= kSamples;
  // Each entry within 5 % of the diagonal's scale (sampling error ~1 % at this count).
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      const double scale = std::sqrt(predicted(i, i) * predicted(j, j));
      EXPECT_NEAR(predicted(i, j), sampled(i, j), 0.05 * scale) << "entry " << i << "," << j;
    }
  }
}

TEST(OdometryFactor, TheFloorBoundsTheInformation) {
  const liod::Matrix6d information = liod::relative_pose_information(liod::Matrix6d::Zero(), 0.01, 0.001);
  EXPECT_NEAR(information(0, 0), 1e4, 1e-6);
  EXPECT_NEAR(information(5, 5), 1e6, 1e-3);
}

}  // namespace
