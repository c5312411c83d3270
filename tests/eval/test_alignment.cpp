#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "liod/eval/alignment.hpp"
#include "liod/eval/io.hpp"
#include "liod/eval/metrics.hpp"
#include "synthetic.hpp"

namespace liod::eval {
namespace {

Poses transformed(const Poses& in, const Eigen::Matrix3d& R, const Eigen::Vector3d& t, double s) {
  Similarity T;
  T.R = R;
  T.t = t;
  T.scale = s;
  return apply_similarity(T, in);
}

const Eigen::Matrix3d kRot =
    Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();

TEST(Umeyama, CoplanarClosedFormCase) {
  // x: the four points (+-1, 0, 0), (0, +-1, 0); y: the same with the first two sheared by +-eps in y.
  // Sigma_xy = [[1/2, 0], [eps/2, 1/2]] in the plane, so the best rotation is about z by
  // atan((S10 - S01) / (S00 + S11)) = atan(eps / 2), the sum of singular values is
  // sqrt((S00 + S11)^2 + (S10 - S01)^2) = sqrt(1 + eps^2 / 4), sigma_x^2 = 1, and both centroids are 0.
  const double eps = 0.2;
  Eigen::Matrix3Xd x(3, 4);
  Eigen::Matrix3Xd y(3, 4);
  x << 1, -1, 0, 0, 0, 0, 1, -1, 0, 0, 0, 0;
  y << 1, -1, 0, 0, eps, -eps, 1, -1, 0, 0, 0, 0;
  const Similarity T = umeyama(x, y, true);
  const Eigen::Matrix3d expect = Eigen::AngleAxisd(std::atan(eps / 2), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_NEAR((T.R - expect).norm(), 0.0, 1e-12);
  EXPECT_NEAR(T.scale, std::sqrt(1.0 + eps * eps / 4.0), 1e-12);
  EXPECT_NEAR(T.t.norm(), 0.0, 1e-12);
  EXPECT_FALSE(T.degenerate);  // rank 2 is enough for a unique rotation (Umeyama's eq. 43)
}

TEST(Umeyama, RecoversAnExactSimilarity) {
  const Poses gt = test::wiggly(40);
  Eigen::Matrix3Xd x(3, 40);
  Eigen::Matrix3Xd y(3, 40);
  const Eigen::Vector3d t(5, -3, 1.5);
  for (int i = 0; i < 40; ++i) {
    x.col(i) = gt[static_cast<std::size_t>(i)].translation();
    y.col(i) = 0.37 * kRot * x.col(i) + t;
  }
  const Similarity T = umeyama(x, y, true);
  EXPECT_NEAR((T.R - kRot).norm(), 0.0, 1e-9);
  EXPECT_NEAR(T.scale, 0.37, 1e-9);
  EXPECT_NEAR((T.t - t).norm(), 0.0, 1e-9);
}

TEST(Umeyama, AgreesWithEigenOnNoisyPointsAndNeverReflects) {
  std::srand(7);
  Eigen::Matrix3Xd x = Eigen::Matrix3Xd::Random(3, 30) * 10.0;
  // A mirror image plus noise: the best orthogonal map is a reflection, which Umeyama's S excludes.
  Eigen::Matrix3Xd y = Eigen::Vector3d(-1, 1, 1).asDiagonal() * x + Eigen::Matrix3Xd::Random(3, 30) * 0.1;
  for (const bool scale : {false, true}) {
    const Similarity T = umeyama(x, y, scale);
    const Eigen::Matrix4d E = Eigen::umeyama(x, y, scale);
    EXPECT_NEAR(T.R.determinant(), 1.0, 1e-12);
    EXPECT_NEAR((T.scale * T.R - E.topLeftCorner<3, 3>()).norm(), 0.0, 1e-9);
    EXPECT_NEAR((T.t - E.topRightCorner<3, 1>()).norm(), 0.0, 1e-9);
  }
}

TEST(Umeyama, FlagsCollinearPoints) {
  Eigen::Matrix3Xd x(3, 5);
  for (int i = 0; i < 5; ++i) x.col(i) = Eigen::Vector3d(i, 0, 0);
  EXPECT_TRUE(umeyama(x, x, false).degenerate);
}

TEST(Alignment, AteWithoutAlignmentEqualsAKnownOffset) {
  // Four poses on a unit square; the estimate is shifted by (0.3, -0.4, 0): every error is 0.5 m.
  const Poses gt = {test::pose(0, 0, 0), test::pose(1, 0, 0), test::pose(1, 1, 0), test::pose(0, 1, 0)};
  Poses est;
  for (const auto& p : gt) est.push_back(Eigen::Translation3d(0.3, -0.4, 0.0) * p);
  const Alignment a = align(gt, est, {AlignMode::None, 0});
  const AteResult ate = compute_ate(gt, apply_similarity(a.transform, est));
  EXPECT_NEAR(ate.translation.rmse, 0.5, 1e-12);
  EXPECT_NEAR(ate.translation.mean, 0.5, 1e-12);
  EXPECT_NEAR(ate.translation.median, 0.5, 1e-12);
  EXPECT_NEAR(ate.translation.std, 0.0, 1e-12);
  EXPECT_NEAR(ate.translation.min, 0.5, 1e-12);
  EXPECT_NEAR(ate.translation.max, 0.5, 1e-12);
  EXPECT_NEAR(ate.rotation.max, 0.0, 1e-12);
  // SE(3) alignment removes a pure offset completely.
  const Alignment se3 = align(gt, est, {AlignMode::SE3, 0});
  EXPECT_NEAR(compute_ate(gt, apply_similarity(se3.transform, est)).translation.max, 0.0, 1e-12);
}

TEST(Alignment, Se3RemovesARigidMotion) {
  const Poses gt = test::wiggly(60);
  const Poses est = transformed(gt, kRot, Eigen::Vector3d(100, -50, 3), 1.0);
  const Alignment a = align(gt, est, {AlignMode::SE3, 0});
  const AteResult ate = compute_ate(gt, apply_similarity(a.transform, est));
  EXPECT_NEAR(ate.translation.max, 0.0, 1e-9);
  EXPECT_NEAR(ate.rotation.max, 0.0, 1e-6);  // degrees
  EXPECT_NEAR((a.transform.R - kRot.transpose()).norm(), 0.0, 1e-9);
  EXPECT_EQ(a.transform.scale, 1.0);
}

TEST(Alignment, ScaledCopyNeedsSim3AndRecoversTheScale) {
  const Poses gt = test::wiggly(60);
  const Poses est = transformed(gt, kRot, Eigen::Vector3d(1, 2, 3), 0.5);  // estimate at half size
  const Alignment se3 = align(gt, est, {AlignMode::SE3, 0});
  EXPECT_GT(compute_ate(gt, apply_similarity(se3.transform, est)).translation.rmse, 1.0);
  const Alignment sim3 = align(gt, est, {AlignMode::Sim3, 0});
  EXPECT_NEAR(sim3.transform.scale, 2.0, 1e-9);
  const AteResult ate = compute_ate(gt, apply_similarity(sim3.transform, est));
  EXPECT_NEAR(ate.translation.max, 0.0, 1e-9);
  EXPECT_NEAR(ate.rotation.max, 0.0, 1e-6);
}

TEST(Alignment, FirstPoseOnlyMakesTheStartsCoincide) {
  const Poses gt = test::wiggly(30);
  Poses est = transformed(gt, kRot, Eigen::Vector3d(4, 5, 6), 1.0);
  est[10].translation() += Eigen::Vector3d(0, 0, 1);  // a later error must not move the alignment
  const Alignment a = align(gt, est, {AlignMode::SE3, 1});
  EXPECT_EQ(a.pairs_used, 1U);
  const Poses aligned = apply_similarity(a.transform, est);
  EXPECT_TRUE(aligned[0].isApprox(gt[0], 1e-12));
  const AteResult ate = compute_ate(gt, aligned);
  EXPECT_NEAR(ate.translation_m[10], 1.0, 1e-9);
  EXPECT_NEAR(ate.translation_m[11], 0.0, 1e-9);
  EXPECT_THROW(align(gt, est, {AlignMode::Sim3, 1}), InputError);
}

TEST(Alignment, FirstNPosesIgnoresLaterDrift) {
  const Poses gt = test::wiggly(50);
  Poses est = transformed(gt, kRot, Eigen::Vector3d(4, 5, 6), 1.0);
  for (std::size_t i = 20; i < est.size(); ++i) est[i].translation() += Eigen::Vector3d(0.1 * (i - 19.0), 0, 0);
  const Alignment first = align(gt, est, {AlignMode::SE3, 20});
  EXPECT_EQ(first.pairs_used, 20U);
  const AteResult ate = compute_ate(gt, apply_similarity(first.transform, est));
  EXPECT_NEAR(ate.translation_m[19], 0.0, 1e-9);
  EXPECT_NEAR(ate.translation_m[49], 3.0, 1e-9);
}

}  // namespace
}  // namespace liod::eval
