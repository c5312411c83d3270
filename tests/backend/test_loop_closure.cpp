// Loop candidates (2D vs 3D), the Hausdorff similarity check and the vertical check on synthetic
// scenes: a revisit of the same street must close; a parallel street and another level must not.

#include <gtest/gtest.h>

#include <random>

#include "liod/angles.hpp"
#include "liod/backend/backend.hpp"
#include "liod/backend/loop_closure.hpp"
#include "synthetic_world.hpp"

namespace {

using namespace liod;
using liod::test::World;
AlgorithmConfig test_config() {
  AlgorithmConfig c;
  c.backend.enabled = true;
  return c;
}

// Street A along x at y = 0: facades at y = -7 (south) and a 4 m high median wall at y = +4.5.
// Street B, parallel at y = 9: the same wall to its south and other facades at y = 16. The
// synthetic scans have no occlusion, so each street's scans see only its own world (the wall
// hides the other street).
World street(bool b) {
  World w;
  std::mt19937 rng(b ? 12 : 11);
  liod::test::add_ground(w, -60, 60, b ? 4.8 : -10, b ? 20 : 4.5, 0.0, 0.3);
  liod::test::add_box(w, {Eigen::Vector3d(-60, 4.5, 0), Eigen::Vector3d(60, 4.8, 4.0)}, 0.3);
  if (!b) {
    liod::test::add_facade_row(w, -60, 60, -7.0, -1.0, rng, 0.3);
    for (double x = -55; x < 60; x += 6.0) liod::test::add_box(w, {Eigen::Vector3d(x, 2.5, 0), Eigen::Vector3d(x + 0.4, 2.9, 3.0)}, 0.2);
  } else {
    liod::test::add_facade_row(w, -60, 60, 16.0, 1.0, rng, 0.3);
    for (double x = -50; x < 60; x += 17.0) liod::test::add_box(w, {Eigen::Vector3d(x, 11.5, 0), Eigen::Vector3d(x + 0.4, 11.9, 3.0)}, 0.2);
  }
  return w;
}

// Sub-map: candidate keyframes along street A at x = -10..10 (true poses = graph poses).
struct Scene {
  std::vector<BackendKeyframe> keyframes;
  std::vector<Eigen::Isometry3d> poses;
};

Scene street_a_submap(const World& w) {
  Scene s;
  for (int i = 0; i <= 10; ++i) {
    const auto pose = liod::test::pose_xyz_yaw(-10.0 + 2.0 * i, 0.0, 0.0, 0.0);
    s.keyframes.push_back(liod::test::to_backend(liod::test::make_keyframe(w, pose, pose, static_cast<std::uint64_t>(i), i * 0.2), 0.3));
    s.poses.push_back(pose);
  }
  return s;
}

// Appends the current keyframe: truly at `truth`, believed (graph) at `graph`, 100 s later.
std::size_t add_current(Scene& s, const World& w, const Eigen::Isometry3d& truth, const Eigen::Isometry3d& graph) {
  s.keyframes.push_back(liod::test::to_backend(liod::test::make_keyframe(w, truth, graph, 100, 100.0), 0.3));
  s.poses.push_back(graph);
  return s.keyframes.size() - 1;
}

TEST(LoopCandidates, TwoDimensionalDistanceIgnoresHeight) {
  std::vector<Eigen::Isometry3d> poses = {liod::test::pose_xyz_yaw(0, 0, 0, 0),     // below, old
                                          liod::test::pose_xyz_yaw(30, 0, 0, 0),    // far, old
                                          liod::test::pose_xyz_yaw(2, 1, 4.0, 0),   // ramp level above, old
                                          liod::test::pose_xyz_yaw(1, 0, 4.0, 0),   // too recent
                                          liod::test::pose_xyz_yaw(0, 0, 4.0, 0)};  // current
  const std::vector<double> times = {0.0, 10.0, 20.0, 95.0, 100.0};
  BackendConfig b;
  b.loop_radius_m = 10.0;
  b.loop_time_gap_s = 20.0;
  b.submap_keyframes = 0;
  b.loop_distance = LoopDistance::k2D;
  auto c2 = loop_candidates(poses, times, 4, b, 5);
  ASSERT_EQ(c2.size(), 2U);
  EXPECT_EQ(c2[0], 0U);  // nearest in x-y first
  EXPECT_EQ(c2[1], 2U);
  b.loop_distance = LoopDistance::k3D;
  auto c3 = loop_candidates(poses, times, 4, b, 5);
  ASSERT_EQ(c3.size(), 2U);
  EXPECT_EQ(c3[0], 2U);  // 3D: the keyframe 4 m below is farther than the one beside
  EXPECT_EQ(c3[1], 0U);
  b.loop_radius_m = 3.0;
  EXPECT_EQ(loop_candidates(poses, times, 4, b, 5), std::vector<std::size_t>{2});
  b.loop_distance = LoopDistance::k2D;
  EXPECT_EQ(loop_candidates(poses, times, 4, b, 5), (std::vector<std::size_t>{0, 2}));
}

TEST(PartialHausdorff, QuantileOneIsTheClassicDistance) {
  std::vector<Eigen::Vector3d> a, b;
  for (int i = 0; i < 100; ++i) {
    a.emplace_back(i * 0.1, 0, 0);
    b.emplace_back(i * 0.1, 0.05, 0);
  }
  b.emplace_back(0, 3.0, 0);  // one outlier
  EXPECT_NEAR(partial_hausdorff(a, b, 1.0, 10.0), 3.0, 1e-9);
  EXPECT_NEAR(partial_hausdorff(a, b, 0.9, 10.0), 0.05, 1e-9);
}

TEST(LoopCheck, RevisitOfTheSameStreetCloses) {
  const World w = street(false);
  Scene s = street_a_submap(w);
  // Truly 3 m along street A, believed 1.2 m / 0.8 m / 1 deg off (drift).
  const auto truth = liod::test::pose_xyz_yaw(3.0, 0.3, 0.0, 2.0 * kDegToRad);
  const auto graph = liod::test::pose_xyz_yaw(4.2, -0.5, 0.15, 3.0 * kDegToRad);
  const std::size_t current = add_current(s, w, truth, graph);
  const LoopCheck check = check_loop(s.keyframes, s.poses, current, 5, test_config());
  ASSERT_EQ(check.outcome, LoopOutcome::kAccepted)
      << to_string(check.outcome) << " similarity " << check.similarity_m << " rms " << check.rms_m << " inliers "
      << check.inlier_fraction << " converged " << check.converged << " degenerate " << check.degenerate_directions;
  EXPECT_LT(check.similarity_m, 1.0);
  const Eigen::Isometry3d expected = s.poses[5].inverse() * truth;
  EXPECT_LT((check.measured.translation() - expected.translation()).norm(), 0.05);
  EXPECT_LT(Eigen::AngleAxisd(check.measured.linear().transpose() * expected.linear()).angle(), 0.2 * kDegToRad);
}

TEST(LoopCheck, ParallelStreetIsDissimilar) {
  Scene s = street_a_submap(street(false));
  // On street B, 9 m north of the candidate: within the 10 m loop radius.
  const auto truth = liod::test::pose_xyz_yaw(0.0, 9.0, 0.0, 0.0);
  const std::size_t current = add_current(s, street(true), truth, truth);
  const AlgorithmConfig config = test_config();
  std::vector<double> times;
  for (const auto& k : s.keyframes) times.push_back(k.time);
  EXPECT_FALSE(loop_candidates(s.poses, times, current, config.backend, 1).empty());
  const LoopCheck check = check_loop(s.keyframes, s.poses, current, 5, config);
  EXPECT_EQ(check.outcome, LoopOutcome::kDissimilar) << to_string(check.outcome) << " similarity " << check.similarity_m;
  EXPECT_GT(check.similarity_m, config.backend.similarity_threshold_m);
}

// A parking ramp: the same structure (floor, walls, pillars) built along a 3 deg slope, next to
// a level deck below it. Registration can fit the level scan onto the sloped structure, but the
// pitch it implies contradicts gravity (the graph's tilt): the vertical check must reject it.
TEST(LoopCheck, VerticalCheckRejectsASlopedLookAlike) {
  World deck;
  std::mt19937 rng(5);
  liod::test::add_ground(deck, -30, 30, -12, 12, 0.0, 0.3);
  liod::test::add_box(deck, {Eigen::Vector3d(-30, -12, 0), Eigen::Vector3d(30, -11.7, 2.5)}, 0.3);
  liod::test::add_box(deck, {Eigen::Vector3d(-30, 11.7, 0), Eigen::Vector3d(30, 12, 2.5)}, 0.3);
  for (double x = -25; x <= 25; x += 8.0) {
    for (double y : {-6.0, 6.0}) liod::test::add_box(deck, {Eigen::Vector3d(x, y, 0), Eigen::Vector3d(x + 0.5, y + 0.5, 2.5)}, 0.25);
  }
  liod::test::add_box(deck, {Eigen::Vector3d(-5, -3, 0), Eigen::Vector3d(-2, 1, 1.5)}, 0.25);  // a parked van
  liod::test::add_box(deck, {Eigen::Vector3d(12, -8, 0), Eigen::Vector3d(12.3, 8, 2.5)}, 0.25);  // a cross wall
  const Eigen::Isometry3d slope(Eigen::AngleAxisd(3.0 * kDegToRad, Eigen::Vector3d::UnitY()));
  World ramp;  // the deck's structure, tilted
  for (const auto& p : deck.planes) ramp.planes.push_back(slope * p);
  for (const auto& p : deck.edges) ramp.edges.push_back(slope * p);

  Scene s;
  for (int i = 0; i <= 10; ++i) {
    // Candidate keyframes driven up the ramp: their poses pitch with it (the graph knows that).
    const Eigen::Isometry3d pose = slope * liod::test::pose_xyz_yaw(-10.0 + 2.0 * i, 0.0, 0.0, 0.0);
    s.keyframes.push_back(liod::test::to_backend(liod::test::make_keyframe(ramp, pose, pose, static_cast<std::uint64_t>(i), i * 0.2), 0.3));
    s.poses.push_back(pose);
  }
  // Now on the level deck, right beside the ramp's position in x-y.
  const auto level = liod::test::pose_xyz_yaw(1.0, 0.0, 0.0, 0.0);
  const std::size_t current = add_current(s, deck, level, level);
  AlgorithmConfig config = test_config();
  config.backend.similarity_check = false;  // isolate the vertical check
  const LoopCheck check = check_loop(s.keyframes, s.poses, current, 5, config);
  EXPECT_EQ(check.outcome, LoopOutcome::kVerticalDisagreement)
      << to_string(check.outcome) << " rms " << check.rms_m << " inliers " << check.inlier_fraction << " tilt "
      << check.tilt_deg << " dz " << check.dz_m << " converged " << check.converged << " degenerate "
      << check.degenerate_directions;
  EXPECT_GT(check.tilt_deg, config.backend.max_tilt_deg);
}

// Two levels of a parking deck 3 m apart with the same layout: the 2D candidate search finds
// the level below, the similarity check rejects it (the coarse search spans only +- half the
// vertical limit in z), and even without it the loop is not accepted.
TEST(LoopCheck, OtherLevelOfADeckDoesNotClose) {
  World lower;
  liod::test::add_ground(lower, -30, 30, -12, 12, 0.0, 0.3);
  for (double x = -25; x <= 25; x += 8.0) {
    for (double y : {-6.0, 6.0}) liod::test::add_box(lower, {Eigen::Vector3d(x, y, 0), Eigen::Vector3d(x + 0.5, y + 0.5, 2.6)}, 0.25);
  }
  liod::test::add_box(lower, {Eigen::Vector3d(-30, -12, 0), Eigen::Vector3d(30, -11.7, 2.6)}, 0.3);
  World both = lower;
  for (const auto& p : lower.planes) both.planes.push_back(p + Eigen::Vector3d(0, 0, 3.0));
  for (const auto& p : lower.edges) both.edges.push_back(p + Eigen::Vector3d(0, 0, 3.0));
  // The level below is seen through nothing from above and vice versa: one world per level.
  World upper;
  for (const auto& p : lower.planes) upper.planes.push_back(p + Eigen::Vector3d(0, 0, 3.0));
  for (const auto& p : lower.edges) upper.edges.push_back(p + Eigen::Vector3d(0, 0, 3.0));
  (void)both;

  Scene s;
  for (int i = 0; i <= 10; ++i) {
    const auto pose = liod::test::pose_xyz_yaw(-10.0 + 2.0 * i, 0.0, 0.0, 0.0);
    s.keyframes.push_back(liod::test::to_backend(liod::test::make_keyframe(lower, pose, pose, static_cast<std::uint64_t>(i), i * 0.2), 0.3));
    s.poses.push_back(pose);
  }
  const auto truth = liod::test::pose_xyz_yaw(0.0, 0.0, 3.0, 0.0);
  const std::size_t current = add_current(s, upper, truth, truth);
  std::vector<double> times;
  for (const auto& k : s.keyframes) times.push_back(k.time);
  AlgorithmConfig config = test_config();
  EXPECT_FALSE(loop_candidates(s.poses, times, current, config.backend, 1).empty());  // 2D: a candidate
  config.backend.loop_distance = LoopDistance::k3D;
  config.backend.loop_radius_m = 2.5;
  EXPECT_TRUE(loop_candidates(s.poses, times, current, config.backend, 1).empty());   // 3D: none
  config = test_config();
  const LoopCheck check = check_loop(s.keyframes, s.poses, current, 5, config);
  EXPECT_EQ(check.outcome, LoopOutcome::kDissimilar) << to_string(check.outcome) << " " << check.similarity_m;
  config.backend.similarity_check = false;
  const LoopCheck unchecked = check_loop(s.keyframes, s.poses, current, 5, config);
  EXPECT_NE(unchecked.outcome, LoopOutcome::kAccepted) << "dz " << unchecked.dz_m;
}

}  // namespace
