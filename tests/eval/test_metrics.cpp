#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "liod/eval/io.hpp"
#include "liod/eval/metrics.hpp"
#include "synthetic.hpp"

namespace liod::eval {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::vector<double> seconds(std::size_t n, double dt) {
  std::vector<double> s;
  for (std::size_t i = 0; i < n; ++i) s.push_back(dt * static_cast<double>(i));
  return s;
}

TEST(Stats, MatchesNumpyConventions) {
  const auto s = summarize({3.0, 1.0, 4.0, 2.0});
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->mean, 2.5, 1e-15);
  EXPECT_NEAR(s->median, 2.5, 1e-15);  // mean of the two middle values
  EXPECT_NEAR(s->rmse, std::sqrt(30.0 / 4.0), 1e-15);
  EXPECT_NEAR(s->std, std::sqrt(1.25), 1e-15);  // population std, as np.std
  EXPECT_EQ(s->min, 1.0);
  EXPECT_EQ(s->max, 4.0);
  EXPECT_EQ(s->count, 4U);
  EXPECT_FALSE(summarize({}));
}

TEST(Rpe, OnePerturbedPositionGivesTwoKnownErrors) {
  // Pose 2 of 5 is 0.1 m off sideways: the pairs (1,2) and (2,3) each see 0.1 m, the others 0.
  const Poses gt = test::line(5);
  Poses est = gt;
  est[2].translation().y() += 0.1;
  const auto r = compute_rpe(seconds(5, 1.0), gt, est, {1.0, DeltaUnit::Frames});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->pairs, 4U);
  EXPECT_NEAR(r->translation.rmse, std::sqrt(0.02 / 4.0), 1e-12);
  EXPECT_NEAR(r->translation.mean, 0.05, 1e-12);
  EXPECT_NEAR(r->translation.median, 0.05, 1e-12);
  EXPECT_NEAR(r->translation.max, 0.1, 1e-12);
  EXPECT_NEAR(r->translation.min, 0.0, 1e-12);
  EXPECT_NEAR(r->rotation.max, 0.0, 1e-12);
}

TEST(Rpe, OnePerturbedHeadingFollowsEvosDefinition) {
  // Pose 2 yawed by 2 deg in place. E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j):
  //  (1,2): rotation 2 deg, translation 0;
  //  (2,3): rotation 2 deg, translation |Rz(-2deg)(1,0,0) - (1,0,0)| = 2 sin(1 deg).
  const Poses gt = test::line(5);
  Poses est = gt;
  est[2] = test::pose(2, 0, 0, 2.0 * kDeg);
  const auto r = compute_rpe(seconds(5, 1.0), gt, est, {1.0, DeltaUnit::Seconds});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->pairs, 4U);
  EXPECT_NEAR(r->rotation.max, 2.0, 1e-9);
  EXPECT_NEAR(r->rotation.mean, 1.0, 1e-9);
  EXPECT_NEAR(r->translation.max, 2.0 * std::sin(1.0 * kDeg), 1e-12);
  EXPECT_NEAR(r->translation.mean, 2.0 * std::sin(1.0 * kDeg) / 4.0, 1e-12);
}

TEST(Rpe, IsInvariantToARigidMotionOfTheEstimate) {
  const Poses gt = test::wiggly(100);
  Poses est;
  const Eigen::Isometry3d T = test::pose(10, 20, 30, 1.0);
  for (const auto& p : gt) est.push_back(T * p);
  const auto r = compute_rpe(seconds(100, 0.1), gt, est, {1.0, DeltaUnit::Seconds});
  ASSERT_TRUE(r);
  EXPECT_NEAR(r->translation.max, 0.0, 1e-9);
  EXPECT_NEAR(r->rotation.max, 0.0, 1e-6);
}

TEST(RpePairs, FramesSecondsAndMetres) {
  const Poses gt = test::line(11);  // 1 m apart
  const auto f = rpe_pairs(seconds(11, 0.1), gt, {3.0, DeltaUnit::Frames});
  EXPECT_EQ(f, (std::vector<std::pair<std::size_t, std::size_t>>{{0, 3}, {3, 6}, {6, 9}}));
  // 10 Hz stamps written as decimals: 0.1 * 10 may land a hair under 1.0; the slack still counts it.
  const auto s = rpe_pairs(seconds(11, 0.1), gt, {1.0, DeltaUnit::Seconds});
  EXPECT_EQ(s, (std::vector<std::pair<std::size_t, std::size_t>>{{0, 10}}));
  // evo's filter_pairs_by_path: indices where the accumulated path reaches delta; the first is at 2 m.
  const auto m = rpe_pairs(seconds(11, 0.1), gt, {2.0, DeltaUnit::Metres});
  EXPECT_EQ(m, (std::vector<std::pair<std::size_t, std::size_t>>{{2, 4}, {4, 6}, {6, 8}, {8, 10}}));
}

TEST(DistanceTravelled, AScaleErrorIsItsPercentageWhateverTheRigidMotion) {
  const Poses gt = test::wiggly(2001, 0.25);  // 500 m of turns and climbs
  const Eigen::Isometry3d motion = test::pose(100.0, -40.0, 3.0, 0.7);
  Poses est;
  for (const auto& p : gt) {
    Eigen::Isometry3d q = p;
    q.translation() *= 0.99;  // 1 % short
    est.push_back(motion * q);
  }
  const auto d = compute_distance_travelled(gt, est);
  ASSERT_TRUE(d);
  EXPECT_NEAR(d->error_pct, -1.0, 1e-9);
  EXPECT_NEAR(d->estimate_m, 0.99 * d->ground_truth_m, 1e-9);
  EXPECT_GT(d->ground_truth_m, 0.95 * path_distances(gt).back());  // 1 m chords of a gentle curve
  EXPECT_EQ(d->steps, rpe_pairs({}, gt, {1.0, DeltaUnit::Metres}).size());
}

TEST(DistanceTravelled, AStandstillsJitterAddsNothing) {
  // 50 m, a standstill of 100 poses, 50 m more; the estimate jitters 2 cm while standing.
  Poses gt;
  for (int i = 0; i <= 50; ++i) gt.push_back(test::pose(i, 0, 0));
  for (int i = 0; i < 100; ++i) gt.push_back(test::pose(50, 0, 0));
  for (int i = 51; i <= 100; ++i) gt.push_back(test::pose(i, 0, 0));
  Poses est = gt;
  for (std::size_t i = 51; i < 150; ++i) est[i].translation().y() = (i % 2 == 0 ? 0.02 : -0.02);
  const auto d = compute_distance_travelled(gt, est);
  ASSERT_TRUE(d);
  EXPECT_NEAR(d->ground_truth_m, 99.0, 1e-9);  // from the first 1 m crossing on, as rpe_pairs counts
  EXPECT_NEAR(d->error_pct, 0.0, 1e-9);
  // Summed pose to pose, the jitter would read as 2 % too long.
  EXPECT_GT(path_distances(est).back() - path_distances(gt).back(), 1.9);
}

TEST(DistanceTravelled, NoneWithoutMotionAndABadStepIsAnError) {
  const Poses still(10, test::pose(3, 4, 5));
  EXPECT_FALSE(compute_distance_travelled(still, still));
  EXPECT_THROW(compute_distance_travelled(test::line(5), test::line(5), 0.0), InputError);
}

TEST(AteSplit, ErrorsLandOnTheirAxesRoundACurve) {
  // A climbing arc of radius 20 m; the estimate runs 0.3 m ahead, 0.2 m left of it and 0.1 m low.
  // The chord between a pose's neighbours on a circle is the tangent at the pose: the split is exact.
  Poses gt;
  Poses est;
  for (int i = 0; i < 60; ++i) {
    const double a = 0.05 * i;
    const Eigen::Vector3d p(20.0 * std::cos(a), 20.0 * std::sin(a), 0.02 * i);
    const Eigen::Vector3d travel(-std::sin(a), std::cos(a), 0.0);
    const Eigen::Vector3d left = Eigen::Vector3d::UnitZ().cross(travel);
    gt.push_back(test::pose(p.x(), p.y(), p.z()));
    const Eigen::Vector3d q = p + 0.3 * travel + 0.2 * left - 0.1 * Eigen::Vector3d::UnitZ();
    est.push_back(test::pose(q.x(), q.y(), q.z()));
  }
  const auto split = compute_ate_split(gt, est, Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(split);
  // The end poses' one-sided chords turn 0.05 rad less than their tangents: 1 mm of mixing.
  EXPECT_NEAR(split->along.median, 0.3, 1e-9);
  EXPECT_NEAR(split->across.median, 0.2, 1e-9);
  EXPECT_NEAR(split->along.mean, 0.3, 2e-3);
  EXPECT_NEAR(split->across.mean, 0.2, 2e-3);
  EXPECT_NEAR(split->vertical.mean, -0.1, 1e-12);
  EXPECT_NEAR(split->vertical.rmse, 0.1, 1e-12);
  // The three parts hold the whole error.
  const double whole = std::sqrt(0.3 * 0.3 + 0.2 * 0.2 + 0.1 * 0.1);
  const double parts = std::sqrt(std::pow(split->along.rmse, 2) + std::pow(split->across.rmse, 2) +
                                 std::pow(split->vertical.rmse, 2));
  EXPECT_NEAR(parts, whole, 1e-9);
}

TEST(AteSplit, AStandstillKeepsTheHeadingItStartsOrStopsWith) {
  // Standing 5 poses, driving north 10 m, standing 5 poses; the estimate is 0.5 m east all along.
  Poses gt;
  for (int i = 0; i < 5; ++i) gt.push_back(test::pose(0, 0, 0));
  for (int i = 1; i <= 10; ++i) gt.push_back(test::pose(0, i, 0));
  for (int i = 0; i < 5; ++i) gt.push_back(test::pose(0, 10, 0));
  Poses est = gt;
  for (auto& p : est) p.translation().x() += 0.5;
  const auto split = compute_ate_split(gt, est, Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(split);
  EXPECT_NEAR(split->across.mean, -0.5, 1e-12);  // east of a northbound car is its right
  EXPECT_NEAR(split->across.min, -0.5, 1e-12);
  EXPECT_NEAR(split->along.rmse, 0.0, 1e-12);
  // A ground truth that never moves across `up` has no direction of travel.
  const Poses lift = {test::pose(0, 0, 0), test::pose(0, 0, 1), test::pose(0, 0, 2)};
  EXPECT_FALSE(compute_ate_split(lift, lift, Eigen::Vector3d::UnitZ()));
}

TEST(Rpe, TooShortForDeltaIsNotANumber) {
  const Poses gt = test::line(5);
  EXPECT_FALSE(compute_rpe(seconds(5, 0.1), gt, gt, {1.0, DeltaUnit::Seconds}));
  EXPECT_THROW(compute_rpe(seconds(5, 0.1), gt, gt, {0.0, DeltaUnit::Seconds}), InputError);
}

TEST(RotationAngle, AccurateForTinyAndLargeAngles) {
  for (const double a : {1e-9, 1e-5, 0.3, 3.0}) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(a, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    EXPECT_NEAR(rotation_angle(R), a, 1e-15 + 1e-12 * a) << a;
  }
}

}  // namespace
}  // namespace liod::eval
