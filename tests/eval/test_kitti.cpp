#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "liod/eval/kitti.hpp"
#include "synthetic.hpp"

namespace liod::eval {
namespace {

constexpr double kRadPerMToDegPer100m = 180.0 / std::numbers::pi * 100.0;

/// Straight ground truth along x, `n` poses `step` metres apart.
Poses straight(std::size_t n, double step) {
  Poses p;
  for (std::size_t i = 0; i < n; ++i) p.push_back(test::pose(step * static_cast<double>(i), 0, 0));
  return p;
}

/// Segments of length L the devkit finds on 1001 poses 1 m apart with first frames every 10:
/// the last frame is first + L + 1 (strictly more than L), so first <= 999 - L.
std::size_t segment_count(double len) { return static_cast<std::size_t>((999.0 - len) / 10.0) + 1; }

TEST(Kitti, OnePercentScaleErrorOnAStraightKilometre) {
  const Poses gt = straight(1001, 1.0);
  Poses est;
  for (const auto& p : gt) est.push_back(test::pose(1.01 * p.translation().x(), 0, 0));
  const KittiResult r = kitti_odometry_error(gt, est);

  // The devkit's segments are one frame longer than L (first frame *beyond* L) but divide by L, so a
  // 1% scale error reads (L + 1) / L percent per length here; summed as the devkit sums.
  double sum = 0.0;
  std::size_t count = 0;
  ASSERT_EQ(r.per_length.size(), 8U);
  for (const auto& l : r.per_length) {
    ASSERT_TRUE(l.translational_pct);
    EXPECT_EQ(l.segments, segment_count(l.length_m)) << l.length_m;
    EXPECT_NEAR(*l.translational_pct, (l.length_m + 1.0) / l.length_m, 1e-9) << l.length_m;
    EXPECT_NEAR(*l.rotational_deg_per_100m, 0.0, 1e-12);
    sum += static_cast<double>(l.segments) * (l.length_m + 1.0) / l.length_m;
    count += l.segments;
  }
  EXPECT_EQ(r.segments.size(), count);
  ASSERT_TRUE(r.translational_pct);
  EXPECT_NEAR(*r.translational_pct, sum / static_cast<double>(count), 1e-9);
  EXPECT_NEAR(*r.rotational_deg_per_100m, 0.0, 1e-12);
  EXPECT_NEAR(r.gt_length_m, 1000.0, 1e-9);
}

TEST(Kitti, OnePercentScaleErrorIsOnePercentWhenFramesAreDense) {
  // 5 cm apart the one-frame overshoot is negligible: 1.0 % to within 0.0005 %.
  const Poses gt = straight(20001, 0.05);
  Poses est;
  for (const auto& p : gt) est.push_back(test::pose(1.01 * p.translation().x(), 0, 0));
  const KittiResult r = kitti_odometry_error(gt, est);
  ASSERT_TRUE(r.translational_pct);
  EXPECT_NEAR(*r.translational_pct, 1.0, 5e-4);
  EXPECT_LT(std::abs(*r.translational_pct - 1.0), 5e-4);
}

TEST(Kitti, ConstantYawRateErrorGivesItsRate) {
  // The estimate's heading drifts by k rad per metre travelled while its positions are exact: the
  // relative rotation error over a segment is k times the segment's true length, L + 1 here.
  const double k = 0.001;  // rad/m = 5.7296 deg/100 m
  const Poses gt = straight(1001, 1.0);
  Poses est;
  for (const auto& p : gt) est.push_back(test::pose(p.translation().x(), 0, 0, k * p.translation().x()));
  const KittiResult r = kitti_odometry_error(gt, est);
  for (const auto& l : r.per_length) {
    ASSERT_TRUE(l.rotational_deg_per_100m);
    EXPECT_NEAR(*l.rotational_deg_per_100m, k * (l.length_m + 1.0) / l.length_m * kRadPerMToDegPer100m, 1e-9)
        << l.length_m;
  }
  ASSERT_TRUE(r.rotational_deg_per_100m);
  EXPECT_GT(*r.rotational_deg_per_100m, k * kRadPerMToDegPer100m);
  EXPECT_LT(*r.rotational_deg_per_100m, k * 1.01 * kRadPerMToDegPer100m);
}

TEST(Kitti, InvariantToARigidMotionOfTheEstimate) {
  const Poses gt = test::wiggly(1200);
  Poses est;
  const Eigen::Isometry3d T = test::pose(100, -20, 5, 2.0);
  for (const auto& p : gt) est.push_back(T * p);
  const KittiResult r = kitti_odometry_error(gt, est);
  ASSERT_TRUE(r.translational_pct);
  EXPECT_NEAR(*r.translational_pct, 0.0, 1e-9);
  EXPECT_NEAR(*r.rotational_deg_per_100m, 0.0, 1e-6);
}

TEST(Kitti, ShorterThanHundredMetresHasNoNumber) {
  const Poses gt = straight(100, 1.0);  // 99 m
  const KittiResult r = kitti_odometry_error(gt, gt);
  EXPECT_FALSE(r.translational_pct);
  EXPECT_FALSE(r.rotational_deg_per_100m);
  EXPECT_TRUE(r.segments.empty());
  for (const auto& l : r.per_length) EXPECT_FALSE(l.translational_pct);
}

TEST(Kitti, LongerLengthsAreSkippedWhenTheyDoNotFit) {
  const Poses gt = straight(251, 1.0);  // 250 m: only 100 and 200 m segments fit
  const KittiResult r = kitti_odometry_error(gt, gt);
  EXPECT_TRUE(r.per_length[0].translational_pct);
  EXPECT_TRUE(r.per_length[1].translational_pct);
  for (std::size_t i = 2; i < r.per_length.size(); ++i) EXPECT_FALSE(r.per_length[i].translational_pct);
  // First frames 0, 10, ..., with first + 101 <= 250 for 100 m and first + 201 <= 250 for 200 m.
  EXPECT_EQ(r.per_length[0].segments, 15U);
  EXPECT_EQ(r.per_length[1].segments, 5U);
  EXPECT_EQ(r.segments.front().last_frame, 101U);
}

}  // namespace
}  // namespace liod::eval
