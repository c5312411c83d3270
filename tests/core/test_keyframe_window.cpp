#include "liod/angles.hpp"
#include "liod/keyframe_window.hpp"

#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "liod/so3.hpp"

namespace liod {
namespace {

// A stretch of road around (x0, 0, 0): ground 0.5 m apart over 8 x 8 m and a wall at y = 4.
// Coordinates sit at quarter metres, off the 1 m voxels' faces, so that downsampling keeps the
// same points whichever pose they are seen from.
std::vector<Eigen::Vector3d> road(double x0) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 16; ++i) {
    for (int j = 0; j < 16; ++j) points.emplace_back(x0 + 0.25 + 0.5 * i, -3.75 + 0.5 * j, 0.25);
  }
  for (int i = 0; i < 16; ++i) {
    for (int k = 0; k < 4; ++k) points.emplace_back(x0 + 0.25 + 0.5 * i, 4.25, 0.75 + 0.5 * k);
  }
  return points;
}

NavState pose(const Eigen::Vector3d& position, double yaw_deg = 0.0) {
  NavState s;
  s.position = position;
  s.rotation = so3::exp(Eigen::Vector3d(0, 0, yaw_deg * kDegToRad));
  return s;
}

// What the scan at `state` holds of world points: planes and map planes, and a few edges.
DeskewedFeatures seen_from(const NavState& state, const std::vector<Eigen::Vector3d>& planes_world,
                           const std::vector<Eigen::Vector3d>& edges_world = {}) {
  DeskewedFeatures f;
  for (const auto& p : planes_world) f.planes.push_back(state.rotation.transpose() * (p - state.position));
  for (const auto& p : edges_world) f.edges.push_back(state.rotation.transpose() * (p - state.position));
  f.map_planes = f.planes;
  return f;
}

bool map_has_point_near(const LocalMap& map, const Eigen::Vector3d& p) {
  std::array<Eigen::Vector3d, LocalMap::kMaxNeighbours> out;
  return map.nearest(p, 1, 0.1, out) == 1;
}

KeyframeWindowConfig distance_angle_config() {
  KeyframeWindowConfig c;
  c.gating = KeyframeGating::kDistanceAngle;
  return c;
}

TEST(KeyframeWindow, TheFirstScanIsAlwaysAKeyframe) {
  KeyframeWindow window(KeyframeWindowConfig{});
  const NavState state = pose({3.0, 1.0, 0.0}, 40.0);
  const auto planes = road(0.0);
  const std::vector<Eigen::Vector3d> edges = {{2.25, 4.25, 2.75}, {6.25, 4.25, 2.75}};
  double hausdorff = -1.0;
  EXPECT_TRUE(window.consider(seen_from(state, planes, edges), state, hausdorff));
  EXPECT_EQ(hausdorff, -1.0) << "no test ran";
  ASSERT_EQ(window.keyframes().size(), 1U);
  EXPECT_EQ(window.plane_map().size(), planes.size());
  EXPECT_EQ(window.edge_map().size(), edges.size());
  // The maps hold the world points: the body-frame features placed at the state.
  for (const auto& p : planes) EXPECT_TRUE(map_has_point_near(window.plane_map(), p));
  for (const auto& p : edges) EXPECT_TRUE(map_has_point_near(window.edge_map(), p));
  EXPECT_TRUE(window.post_axis_map().empty()) << "no post viewpoint configured";
}

// A candidate after 1 m of motion or 10 deg of turn since the last keyframe (not the last scan).
TEST(KeyframeWindow, DistanceAngleGateNeedsAMetreOrTenDegrees) {
  KeyframeWindow window(distance_angle_config());
  const auto planes = road(0.0);
  double hausdorff = -1.0;
  ASSERT_TRUE(window.consider(seen_from(pose({0, 0, 0}), planes), pose({0, 0, 0}), hausdorff));
  EXPECT_FALSE(window.consider(seen_from(pose({0.9, 0, 0}), planes), pose({0.9, 0, 0}), hausdorff));
  EXPECT_FALSE(window.consider(seen_from(pose({0, 0, 0}, 9.0), planes), pose({0, 0, 0}, 9.0), hausdorff));
  EXPECT_FALSE(window.consider(seen_from(pose({0.6, 0.6, 0}), planes), pose({0.6, 0.6, 0}), hausdorff)) << "0.85 m";
  EXPECT_EQ(window.keyframes().size(), 1U);
  EXPECT_TRUE(window.consider(seen_from(pose({0.8, 0.8, 0}), planes), pose({0.8, 0.8, 0}), hausdorff)) << "1.13 m";
  EXPECT_TRUE(window.consider(seen_from(pose({0.8, 0.8, 0}, 11.0), planes), pose({0.8, 0.8, 0}, 11.0), hausdorff));
  EXPECT_EQ(window.keyframes().size(), 3U);
  EXPECT_EQ(hausdorff, -1.0) << "the distance/angle gate runs no Hausdorff test";
}

// Past the distance gate, a candidate that shows the scene of the last keyframe (from 2 m on)
// adds nothing and is rejected with a distance of ~0; one that shows a new wall 1.5 m off
// everything the last keyframe saw is accepted, its distance at least those 1.5 m.
TEST(KeyframeWindow, HausdorffGateRejectsTheSameSceneAndAcceptsADifferentOne) {
  KeyframeWindow window(KeyframeWindowConfig{});
  const auto scene = road(0.0);
  double hausdorff = -1.0;
  ASSERT_TRUE(window.consider(seen_from(pose({0, 0, 0}), scene), pose({0, 0, 0}), hausdorff));

  const NavState moved = pose({2.0, 0.5, 0.0}, 15.0);
  EXPECT_FALSE(window.consider(seen_from(moved, scene), moved, hausdorff));
  EXPECT_LT(hausdorff, 1e-6);
  EXPECT_EQ(window.keyframes().size(), 1U);

  auto changed = scene;
  for (int i = 0; i < 8; ++i) {
    for (int k = 0; k < 3; ++k) changed.emplace_back(4.25, -1.75 + 0.5 * i, 1.75 + 0.5 * k);  // z >= 1.75
  }
  EXPECT_TRUE(window.consider(seen_from(moved, changed), moved, hausdorff));
  EXPECT_GE(hausdorff, 1.5 - 1e-9);
  EXPECT_LE(hausdorff, 4.0 * 0.6 + 1e-9) << "saturated at 4 h1";
  EXPECT_EQ(window.keyframes().size(), 2U);
}

// With room for three, the fourth keyframe pushes out the first, and the first's points leave
// every map; only the newest keyframe keeps its similarity cloud and IMU stretch.
TEST(KeyframeWindow, TheWindowEvictsTheOldestKeyframeAndItsPoints) {
  KeyframeWindowConfig config = distance_angle_config();
  config.window_keyframes = 3;
  KeyframeWindow window(config);
  std::vector<std::vector<Eigen::Vector3d>> roads;
  std::vector<Eigen::Vector3d> edges;
  double hausdorff = 0.0;
  for (int k = 0; k < 4; ++k) {
    roads.push_back(road(10.0 * k));
    edges.emplace_back(10.0 * k + 1.25, 4.25, 2.75);
    const NavState state = pose({10.0 * k + 4.0, 0.0, 0.0});
    ASSERT_TRUE(window.consider(seen_from(state, roads.back(), {edges.back()}), state, hausdorff));
    window.set_newest_for_backend(PoseCovariance::Identity(), std::vector<ImuInterval>(3));
    if (k == 2) {
      EXPECT_EQ(window.plane_map().size(), 3 * roads[0].size());
    }
  }
  ASSERT_EQ(window.keyframes().size(), 3U);
  EXPECT_EQ(window.keyframes().front().id, 1U);
  EXPECT_EQ(window.keyframes().back().id, 3U);
  EXPECT_EQ(window.plane_map().size(), 3 * roads[0].size());
  EXPECT_EQ(window.edge_map().size(), 3U);
  for (const auto& p : roads[0]) EXPECT_FALSE(map_has_point_near(window.plane_map(), p));
  EXPECT_FALSE(map_has_point_near(window.edge_map(), edges[0]));
  for (const auto& p : roads[3]) EXPECT_TRUE(map_has_point_near(window.plane_map(), p));
  EXPECT_TRUE(map_has_point_near(window.edge_map(), edges[3]));

  EXPECT_TRUE(window.keyframes()[0].similarity_cloud_world.empty());
  EXPECT_TRUE(window.keyframes()[1].similarity_cloud_world.empty());
  EXPECT_FALSE(window.keyframes()[2].similarity_cloud_world.empty());
  EXPECT_TRUE(window.keyframes()[1].imu_since_previous.empty()) << "sent to the backend with its keyframe";
  EXPECT_EQ(window.keyframes()[2].imu_since_previous.size(), 3U);
  EXPECT_EQ(window.keyframes()[1].pose_covariance, PoseCovariance::Identity());
  EXPECT_FALSE(window.keyframes()[2].planes_world.empty()) << "the map points stay with every keyframe";
}

TEST(KeyframeWindow, RestartEmptiesTheWindowAndTheMaps) {
  KeyframeWindowConfig config;
  config.post_viewpoint_body = Eigen::Vector3d(0.0, 0.0, 1.5);
  KeyframeWindow window(config);
  const NavState state = pose({0, 0, 0});
  const auto planes = road(0.0);
  const std::vector<Eigen::Vector3d> edges = {{5.25, 4.25, 0.75}};
  double hausdorff = 0.0;
  ASSERT_TRUE(window.consider(seen_from(state, planes, edges), state, hausdorff));
  ASSERT_FALSE(window.post_axis_map().empty());
  window.restart();
  EXPECT_TRUE(window.keyframes().empty());
  EXPECT_TRUE(window.plane_map().empty());
  EXPECT_TRUE(window.edge_map().empty());
  EXPECT_TRUE(window.post_axis_map().empty());
  // The next scan starts the map afresh, even where the last keyframe stood.
  EXPECT_TRUE(window.consider(seen_from(state, planes, edges), state, hausdorff));
  EXPECT_EQ(window.plane_map().size(), planes.size());
}

// With posts: an edge at 10 m straight ahead of the LiDAR (1.5 m above the body) has its post's
// axis post_depth_m further along the horizontal ray, at the edge's height.
TEST(KeyframeWindow, PostAxesLieBehindTheEdgesAlongTheHorizontalRay) {
  KeyframeWindowConfig config;
  config.post_viewpoint_body = Eigen::Vector3d(0.0, 0.0, 1.5);
  config.post_depth_m = 0.08;
  KeyframeWindow window(config);
  const NavState state = pose({5.0, 2.0, 0.0}, 90.0);  // facing world +y
  const std::vector<Eigen::Vector3d> edges = {{5.0, 12.0, 0.4}};
  double hausdorff = 0.0;
  ASSERT_TRUE(window.consider(seen_from(state, road(0.0), edges), state, hausdorff));
  const auto& axes = window.keyframes().back().post_axes_world;
  ASSERT_EQ(axes.size(), 1U);
  EXPECT_LT((axes[0] - Eigen::Vector3d(5.0, 12.08, 0.4)).norm(), 1e-9);
  EXPECT_EQ(window.post_axis_map().size(), 1U);
  EXPECT_TRUE(map_has_point_near(window.post_axis_map(), Eigen::Vector3d(5.0, 12.08, 0.4)));
}

}  // namespace
}  // namespace liod
