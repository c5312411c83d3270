#include <gtest/gtest.h>

#include "liod/eval/association.hpp"
#include "liod/eval/io.hpp"
#include "synthetic.hpp"

namespace liod::eval {
namespace {

TEST(Association, NearestAcceptsOffsetsWithinMaxDt) {
  const Trajectory gt = test::stamped(test::line(50), 0.0, 0.1, "gt");
  const Trajectory est = test::stamped(test::line(50), 0.015, 0.1, "est");
  AssociationOptions o;
  o.max_dt = 0.02;
  o.interpolation = Interpolation::Off;
  const Association a = associate(gt, est, o);
  ASSERT_EQ(a.est.size(), 50U);
  EXPECT_FALSE(a.interpolated);
  for (std::size_t i = 0; i < 50; ++i) {
    EXPECT_EQ(a.est_index[i], i);
    EXPECT_EQ(a.gt[i].translation().x(), static_cast<double>(i));
  }
}

TEST(Association, OffsetBeyondMaxDtIsNoOverlapUnlessCorrected) {
  const Trajectory gt = test::stamped(test::line(50), 0.0, 0.1, "gt");
  const Trajectory est = test::stamped(test::line(50), 0.03, 0.1, "est");
  AssociationOptions o;
  o.interpolation = Interpolation::Off;
  try {
    associate(gt, est, o);
    FAIL() << "expected no overlap";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no overlap in time"), std::string::npos) << e.what();
  }
  o.est_time_offset = -0.03;  // evo's --t_offset
  EXPECT_EQ(associate(gt, est, o).est.size(), 50U);
}

TEST(Association, DisjointTimeRangesAreAnError) {
  const Trajectory gt = test::stamped(test::line(10), 0.0, 0.1, "gt");
  const Trajectory est = test::stamped(test::line(10), 100.0, 0.1, "est");
  EXPECT_THROW(associate(gt, est, {}), InputError);
}

TEST(Association, GapsInGroundTruthLeaveEstimatesUnpaired) {
  // Ground truth at 10 Hz with a dropout between 1.0 and 2.0 s.
  Trajectory gt;
  gt.name = "gt";
  for (int i = 0; i <= 30; ++i) {
    const double t = 0.1 * i;
    if (t > 1.05 && t < 1.95) continue;
    gt.stamps.push_back(t);
    gt.poses.push_back(test::pose(t, 0, 0));
  }
  const Trajectory est = test::stamped(test::line(31), 0.0, 0.1, "est");
  AssociationOptions o;
  o.interpolation = Interpolation::Off;
  EXPECT_EQ(associate(gt, est, o).est.size(), 31U - 9U);
  // Interpolation must not bridge the 1 s hole either.
  o.interpolation = Interpolation::On;
  o.max_gap = 0.15;
  EXPECT_EQ(associate(gt, est, o).est.size(), 31U - 9U);
}

TEST(Association, NearestIsOneToOneAndMonotone) {
  // Two estimates at 0.99 and 1.005 both have ground truth 1.0 as nearest: only the closer one pairs.
  Trajectory gt;
  gt.name = "gt";
  for (double t : {0.0, 1.0, 2.0}) {
    gt.stamps.push_back(t);
    gt.poses.push_back(test::pose(t, 0, 0));
  }
  Trajectory est;
  est.name = "est";
  for (double t : {0.0, 0.99, 1.005, 2.0}) {
    est.stamps.push_back(t);
    est.poses.push_back(test::pose(t, 1, 0));
  }
  AssociationOptions o;
  o.interpolation = Interpolation::Off;
  const Association a = associate(gt, est, o);
  ASSERT_EQ(a.est.size(), 3U);
  EXPECT_EQ(a.est_index, (std::vector<std::size_t>{0, 2, 3}));
  EXPECT_EQ(a.gt[1].translation().x(), 1.0);
}

TEST(Association, InterpolatesDenseGroundTruthExactly) {
  // 100 Hz ground truth moving at 2 m/s with a constant yaw rate of 0.3 rad/s: linear position and
  // slerp are both exact for this motion, so the interpolated pose equals the analytic one.
  Poses g;
  for (int i = 0; i <= 1000; ++i) {
    const double t = 0.01 * i;
    g.push_back(test::pose(2.0 * t, -t, 0.5, 0.3 * t));
  }
  const Trajectory gt = test::stamped(g, 0.0, 0.01, "gt");
  Poses e;
  std::vector<double> stamps;
  for (int i = 0; i < 99; ++i) {
    const double t = 0.0037 + 0.1 * i;
    stamps.push_back(t);
    e.push_back(test::pose(0, 0, 0));
  }
  Trajectory est;
  est.name = "est";
  est.stamps = stamps;
  est.poses = e;
  const Association a = associate(gt, est, {});  // auto: ground truth is 10x denser
  EXPECT_TRUE(a.interpolated);
  ASSERT_EQ(a.gt.size(), 99U);
  for (std::size_t k = 0; k < a.gt.size(); ++k) {
    const double t = stamps[k];
    const Eigen::Isometry3d expect = test::pose(2.0 * t, -t, 0.5, 0.3 * t);
    EXPECT_NEAR((a.gt[k].translation() - expect.translation()).norm(), 0.0, 1e-9) << k;
    EXPECT_NEAR((a.gt[k].linear() - expect.linear()).norm(), 0.0, 1e-9) << k;
  }
}

TEST(Association, AutoUsesNearestForEqualRates) {
  const Trajectory gt = test::stamped(test::line(20), 0.0, 0.1, "gt");
  const Trajectory est = test::stamped(test::line(20), 0.0, 0.1, "est");
  EXPECT_FALSE(associate(gt, est, {}).interpolated);
}

TEST(Association, KittiPairsByIndexAndNeedsEqualLengths) {
  Trajectory gt;
  gt.name = "gt";
  gt.poses = test::line(5);
  Trajectory est;
  est.name = "est";
  est.poses = test::line(5);
  const Association a = associate(gt, est, {});
  EXPECT_FALSE(a.by_time);
  EXPECT_EQ(a.est.size(), 5U);
  est.poses.pop_back();
  EXPECT_THROW(associate(gt, est, {}), InputError);
  const Trajectory stamped = test::stamped(test::line(5), 0, 1, "tum");
  EXPECT_THROW(associate(stamped, est, {}), InputError);
}

TEST(Interpolate, HalfwayBetweenTwoPoses) {
  const Eigen::Isometry3d a = test::pose(0, 0, 0, 0.0);
  const Eigen::Isometry3d b = test::pose(2, 4, 6, 1.0);
  const Eigen::Isometry3d m = interpolate(a, b, 0.5);
  EXPECT_TRUE(m.translation().isApprox(Eigen::Vector3d(1, 2, 3), 1e-12));
  EXPECT_NEAR(rotation_angle(m.linear()), 0.5, 1e-12);
}

}  // namespace
}  // namespace liod::eval
