#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "liod/curvature_features.hpp"
#include "ray_box.hpp"

namespace {

using liod::CurvatureNeighbourhood;

TEST(CurvatureFeatures, NeighbourhoodFollowsThePaper) {
  EXPECT_EQ(liod::curvature_neighbourhood_size(5.0, CurvatureNeighbourhood::kDistanceAdaptive), 10);
  EXPECT_EQ(liod::curvature_neighbourhood_size(10.0, CurvatureNeighbourhood::kDistanceAdaptive), 10);
  EXPECT_EQ(liod::curvature_neighbourhood_size(15.0, CurvatureNeighbourhood::kDistanceAdaptive), 8);
  EXPECT_EQ(liod::curvature_neighbourhood_size(25.0, CurvatureNeighbourhood::kDistanceAdaptive), 6);
  EXPECT_EQ(liod::curvature_neighbourhood_size(45.0, CurvatureNeighbourhood::kDistanceAdaptive), 4);
  EXPECT_EQ(liod::curvature_neighbourhood_size(45.0, CurvatureNeighbourhood::kFixed), 10);
}

// One horizontal beam sweeping a rectangular room of 16 x 10 m from its centre.
liod::Scan room_scan() {
  liod::Scan scan;
  scan.beam_count = 1;
  const int n = 1800;
  for (int i = 0; i < n; ++i) {
    const double az = 2.0 * M_PI * i / n;
    const double c = std::cos(az);
    const double s = std::sin(az);
    const double range = std::min(std::abs(8.0 / (std::abs(c) > 1e-9 ? c : 1e-9)), std::abs(5.0 / (std::abs(s) > 1e-9 ? s : 1e-9)));
    liod::LidarPoint p;
    p.x = static_cast<float>(range * c);
    p.y = static_cast<float>(range * s);
    p.time = static_cast<float>(i * 55.56e-6);
    scan.points.push_back(p);
  }
  scan.end_time = scan.points.back().time;
  return scan;
}

TEST(CurvatureFeatures, CornersAreEdgesAndWallsArePlanes) {
  liod::FeatureParams params;
  params.edge_curvature = 0.01;
  params.plane_curvature = 0.002;
  params.max_edges_per_sector = 2;
  params.sectors_per_ring = 4;
  liod::FeatureExtractor extractor(params);
  const liod::Scan scan = room_scan();
  liod::ScanFeatures features;
  extractor.extract(scan, features);
  ASSERT_FALSE(features.edges.empty());
  int at_corners = 0;
  for (auto i : features.edges) {
    const auto& p = scan.points[i];
    if (std::abs(std::abs(p.x) - 8.0F) < 0.3F && std::abs(std::abs(p.y) - 5.0F) < 0.3F) ++at_corners;
  }
  // The room has 4 corners; every one is found (the first sits at the wrap, where a ring has no
  // window on one side, so at least 3).
  EXPECT_GE(at_corners, 3);
  EXPECT_EQ(at_corners, static_cast<int>(features.edges.size()));
  EXPECT_GT(features.planes.size(), 1000U);
  for (auto i : features.planes) {
    const auto& p = scan.points[i];
    const bool on_wall_interior = std::abs(std::abs(p.x) - 8.0F) > 0.2F || std::abs(std::abs(p.y) - 5.0F) > 0.2F;
    EXPECT_TRUE(on_wall_interior);
  }
}

TEST(CurvatureFeatures, OccludedFarSideIsExcluded) {
  liod::Scan scan;
  scan.beam_count = 1;
  // A wall at 10 m with a pole at 3 m in front of it: the wall points right next to the pole's
  // silhouette are the far side of an occlusion and must not become features.
  for (int i = 0; i < 200; ++i) {
    const double az = (i - 100) * 0.2 * M_PI / 180.0;
    const bool pole = i >= 100 && i < 110;
    const double range = pole ? 3.0 : 10.0 / std::cos(az);
    liod::LidarPoint p;
    p.x = static_cast<float>(range * std::cos(az));
    p.y = static_cast<float>(range * std::sin(az));
    p.time = static_cast<float>(i * 55.56e-6);
    scan.points.push_back(p);
  }
  liod::FeatureParams params;
  params.sectors_per_ring = 1;
  params.edge_curvature = 0.01;
  params.plane_curvature = 0.005;
  liod::FeatureExtractor extractor(params);
  liod::ScanFeatures features;
  extractor.extract(scan, features);
  for (auto i : features.edges) EXPECT_TRUE(i >= 100 && i < 110) << "edge at wall index " << i;
  for (auto i : features.planes) EXPECT_TRUE(i < 95 || i >= 115) << "plane next to the occlusion at " << i;
}

using liod::test::box_entry;

// One beam 12.9 deg below the horizon, 1.83 m above a flat road, sweeping past one post standing
// on it: a square of half side `half` turned by `yaw`, or (round) a circle of radius `half`; `count`
// returns 0.2 deg apart from azimuth `first_deg`.
liod::Scan post_scan(const Eigen::Vector2d& centre, double half, double yaw, bool round, double first_deg, int count) {
  liod::Scan scan;
  scan.beam_count = 1;
  const double down = std::tan(12.9 * M_PI / 180.0);
  const double ground = 1.83 / down;
  const Eigen::Rotation2Dd to_post(-yaw);
  for (int i = 0; i < count; ++i) {
    const double az = (first_deg + 0.2 * i) * M_PI / 180.0;
    const Eigen::Vector2d dir(std::cos(az), std::sin(az));
    double reach = ground;
    if (round) {
      // |t dir - centre| = half: t = dir . centre -+ sqrt(...).
      const double b = dir.dot(centre);
      const double disc = b * b - (centre.squaredNorm() - half * half);
      if (disc >= 0.0 && b - std::sqrt(disc) > 0.0) reach = std::min(reach, b - std::sqrt(disc));
    } else {
      // In the post's frame, where the sensor is at -centre turned.
      const auto enter = box_entry(to_post * (-centre), to_post * dir, Eigen::Vector2d(-half, -half),
                                   Eigen::Vector2d(half, half));
      if (enter) reach = std::min(reach, *enter);
    }
    liod::LidarPoint p;
    p.x = static_cast<float>(reach * dir.x());
    p.y = static_cast<float>(reach * dir.y());
    p.z = static_cast<float>(-reach * down);
    p.time = static_cast<float>(i * 55.56e-6);
    scan.points.push_back(p);
  }
  return scan;
}

// One beam 12.9 deg below the horizon, 1.83 m above a flat road, sweeping past a guard-rail post
// (16 cm square, 4.35 m to the right, 4.7 m ahead): the beam meets the post 0.34 m above the road
// at 6.5 m, the ground beside it at 7.95 m. A post below a rail stands out from the ground behind
// it by only 1-1.5 m.
liod::Scan post_before_the_ground_scan() {
  return post_scan(Eigen::Vector2d(4.73, -4.35), 0.08, 0.0, false, -60.1, 400);
}

TEST(CurvatureFeatures, ALowPostBeforeTheGroundIsAnEdge) {
  const liod::Scan scan = post_before_the_ground_scan();
  int on_post = 0;
  for (const auto& p : scan.points) on_post += std::hypot(p.x, p.y) < 7.5F ? 1 : 0;
  ASSERT_GE(on_post, 3);
  liod::FeatureParams params;  // the defaults
  params.sectors_per_ring = 1;
  liod::FeatureExtractor extractor(params);
  liod::ScanFeatures features;
  extractor.extract(scan, features);
  int post_edges = 0;
  for (auto i : features.edges) post_edges += std::hypot(scan.points[i].x, scan.points[i].y) < 7.5F ? 1 : 0;
  EXPECT_GE(post_edges, 1);
  // LOAM's usual threshold does not see it: the post's sharpest points have a curvature of 0.12.
  params.edge_curvature = 0.2;
  liod::FeatureExtractor strict(params);
  strict.extract(scan, features);
  for (auto i : features.edges) EXPECT_GT(std::hypot(scan.points[i].x, scan.points[i].y), 7.5F);
}

// One horizontal beam inside a tunnel looking back at the portal: the right wall, 3.8 m to the
// side, ends 20 m behind the sensor, and past its end the beam reaches the open road 60 m away.
// The wall is met at 10.8 deg, so its returns lie 0.38 m apart and the last one short of the end.
liod::Scan wall_end_at_grazing_scan(double azimuth_phase_deg) {
  liod::Scan scan;
  scan.beam_count = 1;
  for (int i = 0; i < 400; ++i) {
    const double az = (-100.0 - azimuth_phase_deg - 0.2 * i) * M_PI / 180.0;
    const Eigen::Vector2d dir(std::cos(az), std::sin(az));
    const double to_wall = -3.8 / dir.y();
    const double reach = to_wall * dir.x() >= -20.0 ? to_wall : 60.0;
    liod::LidarPoint p;
    p.x = static_cast<float>(reach * dir.x());
    p.y = static_cast<float>(reach * dir.y());
    p.time = static_cast<float>(i * 55.56e-6);
    scan.points.push_back(p);
  }
  return scan;
}

TEST(CurvatureFeatures, AWallsEndSeenAtGrazingIncidenceIsPlacedHalfAStepOn) {
  liod::FeatureParams params;  // the defaults
  params.sectors_per_ring = 1;
  double raw_sum = 0.0;
  double shifted_sum = 0.0;
  double shifted_abs_sum = 0.0;
  const int phases = 10;
  for (int phase = 0; phase < phases; ++phase) {
    const liod::Scan scan = wall_end_at_grazing_scan(0.02 * phase);
    liod::FeatureExtractor extractor(params);
    liod::ScanFeatures features;
    extractor.extract(scan, features);
    ASSERT_EQ(features.edge_shifts.size(), features.edges.size());
    int at_end = 0;
    for (std::size_t e = 0; e < features.edges.size(); ++e) {
      const auto& p = scan.points[features.edges[e]];
      if (std::abs(p.y + 3.8F) > 0.01F || p.x > -19.0F) continue;
      ++at_end;
      // How far short of the wall's end (towards the sensor), before and after the shift.
      raw_sum += static_cast<double>(p.x) + 20.0;
      const double shifted = static_cast<double>(p.x + features.edge_shifts[e].x()) + 20.0;
      shifted_sum += shifted;
      shifted_abs_sum += std::abs(shifted);
      EXPECT_NEAR(p.y + features.edge_shifts[e].y(), -3.8F, 1e-3F) << "moved along the wall";
    }
    EXPECT_EQ(at_end, 1) << "phase " << phase;
  }
  // The last return is on average half a step (0.19 m) short of the end; moved on, on the end.
  EXPECT_GT(raw_sum / phases, 0.12);
  EXPECT_LT(std::abs(shifted_sum / phases), 0.03);
  // Uniform over a step s the last return is s / 2 short on average, and |short - s / 2| is s / 4.
  EXPECT_LT(shifted_abs_sum / phases, 0.65 * raw_sum / phases);

  // Off: the edge stays where the last return was.
  params.surface_end_extrapolation = 0.0;
  liod::FeatureExtractor off(params);
  liod::ScanFeatures features;
  off.extract(wall_end_at_grazing_scan(0.0), features);
  for (const auto& shift : features.edge_shifts) EXPECT_EQ(shift, Eigen::Vector3f::Zero());
}

TEST(CurvatureFeatures, APostSeenFaceOnKeepsItsEdgeWhereTheReturnWas) {
  // Its returns are 2-3 cm apart, about the range noise: the surface-end shift, which moves a
  // grazing surface's last return on, would add noise, not accuracy. (The post model places a
  // post's edges by its axis instead: NarrowRunEdgesArePlacedByTheAxisFromAnySide.)
  const liod::Scan scan = post_before_the_ground_scan();
  liod::FeatureParams params;
  params.sectors_per_ring = 1;
  params.post_max_width_m = 0.0;
  liod::FeatureExtractor extractor(params);
  liod::ScanFeatures features;
  extractor.extract(scan, features);
  int post_edges = 0;
  for (std::size_t e = 0; e < features.edges.size(); ++e) {
    if (std::hypot(scan.points[features.edges[e]].x, scan.points[features.edges[e]].y) >= 7.5F) continue;
    ++post_edges;
    EXPECT_EQ(features.edge_shifts[e], Eigen::Vector3f::Zero());
  }
  EXPECT_GE(post_edges, 1);
}

// Two returns of one ring on a wall along the x axis: the first met at 20 m and grazing_deg, the
// second where the ray turned one step (0.2 deg) further meets the wall.
std::pair<Eigen::Vector3f, Eigen::Vector3f> returns_on_a_wall(double grazing_deg, double step) {
  const double grazing = grazing_deg * M_PI / 180.0;
  const Eigen::Vector3f previous(static_cast<float>(20.0 * std::cos(grazing)), static_cast<float>(20.0 * std::sin(grazing)), 0.0F);
  const double reach = static_cast<double>(previous.y()) / std::sin(grazing - step);
  const Eigen::Vector3f end(static_cast<float>(reach * std::cos(grazing - step)), previous.y(), 0.0F);
  return {previous, end};
}

TEST(CurvatureFeatures, SurfaceEndShiftOnlyAtGrazingIncidence) {
  // Face-on at 10 m, one 0.2 deg step: 3.5 cm, left alone.
  const double step = 0.2 * M_PI / 180.0;
  const Eigen::Vector3f face_on_prev(10.0F, 0.0F, 0.0F);
  const Eigen::Vector3f face_on_end(10.0F, static_cast<float>(10.0 * std::tan(step)), 0.0F);
  EXPECT_EQ(liod::surface_end_shift(face_on_end, face_on_prev, 0.5), Eigen::Vector3f::Zero());
  // A wall met at 10.5 deg: the ray turned one step further meets it 1 / sin(10.5 deg) = 5.5 times
  // as far on as the same turn moves a face-on return.
  const auto [wall_prev, wall_end] = returns_on_a_wall(10.5, step);
  const Eigen::Vector3f shift = liod::surface_end_shift(wall_end, wall_prev, 0.5);
  EXPECT_NEAR(shift.norm(), 0.5F * (wall_end - wall_prev).norm(), 1e-5F);
  EXPECT_NEAR(shift.y(), 0.0F, 1e-5F) << "along the wall";
  EXPECT_EQ(liod::surface_end_shift(wall_end, wall_prev, 0.0), Eigen::Vector3f::Zero());
  // At 15 deg (3.9 times), below the gate: left alone.
  const auto [shallow_prev, shallow_end] = returns_on_a_wall(15.0, step);
  EXPECT_EQ(liod::surface_end_shift(shallow_end, shallow_prev, 0.5), Eigen::Vector3f::Zero());
}

TEST(CurvatureFeatures, NarrowRunEdgesArePlacedByTheAxisFromAnySide) {
  // Guard-rail posts passed at 4.35 m, from 6 m ahead to abeam, square (turned 0 and 30 deg) and
  // round. The post model takes the axis post_depth_m behind an edge along its horizontal ray:
  // from the return itself that is 0-11 cm off depending on the view and the run's end; from the
  // edge the extractor places by the run's axis, within a centimetre or two.
  liod::FeatureParams params;
  params.sectors_per_ring = 1;
  params.post_max_width_m = 0.4;  // depth 0.08 m, the default
  const double depth = params.post_depth_m;
  double worst_placed = 0.0;
  double worst_return = 0.0;
  int posts = 0;
  for (const double ahead : {6.0, 4.35, 2.5, 1.0, 0.0}) {
    for (const auto& [yaw, round] : {std::pair{0.0, false}, std::pair{0.52, false}, std::pair{0.0, true}}) {
      const Eigen::Vector2d centre(ahead, -4.35);
      const liod::Scan scan = post_scan(centre, 0.08, yaw, round, std::atan2(-4.35, ahead) * 180.0 / M_PI - 60.1, 600);
      liod::FeatureExtractor extractor(params);
      liod::ScanFeatures features;
      extractor.extract(scan, features);
      ASSERT_EQ(features.edge_shifts.size(), features.edges.size());
      for (std::size_t e = 0; e < features.edges.size(); ++e) {
        const auto& p = scan.points[features.edges[e]];
        const Eigen::Vector2d at(p.x, p.y);
        if ((at - centre).norm() > 0.3) continue;
        ++posts;
        const Eigen::Vector2d placed = at + features.edge_shifts[e].head<2>().cast<double>();
        const Eigen::Vector2d axis_from_placed = placed + depth * placed.normalized();
        const Eigen::Vector2d axis_from_return = at + depth * at.normalized();
        worst_placed = std::max(worst_placed, (axis_from_placed - centre).norm());
        worst_return = std::max(worst_return, (axis_from_return - centre).norm());
      }
    }
  }
  EXPECT_GE(posts, 12);
  EXPECT_LT(worst_placed, 0.025) << "from the return: " << worst_return;
  EXPECT_GT(worst_return, 0.05) << "placed: " << worst_placed;
}

TEST(CurvatureFeatures, NarrowRunAxisOfARoundAndASquareSection) {
  // Returns 0.2 deg apart on a post's visible side, 6 m away: the axis from them, for a circle
  // and for squares seen face-on, corner-on and in between.
  for (const double yaw : {-1.0, 0.0, 0.3, 0.785}) {
    for (const bool round : {false, true}) {
      const Eigen::Vector2d centre(5.0, 3.3);
      const liod::Scan scan = post_scan(centre, 0.08, yaw, round, std::atan2(3.3, 5.0) * 180.0 / M_PI - 60.1, 600);
      std::vector<float> x, y, z;
      for (const auto& p : scan.points) {
        if (std::hypot(static_cast<double>(p.x) - centre.x(), static_cast<double>(p.y) - centre.y()) > 0.2) continue;
        x.push_back(p.x);
        y.push_back(p.y);
        z.push_back(p.z);
      }
      ASSERT_GE(x.size(), 5U);
      const auto axis = liod::narrow_run_axis(x.data(), y.data(), z.data(), 0, static_cast<int>(x.size()) - 1);
      ASSERT_TRUE(axis.has_value());
      EXPECT_LT((axis->head<2>().cast<double>() - centre).norm(), 0.015) << "yaw " << yaw << (round ? " round" : " square");
    }
  }
  const float one[] = {1.0F};
  EXPECT_FALSE(liod::narrow_run_axis(one, one, one, 0, 0).has_value());
}

// A guard rail passed in the slow lane, LiDAR 1.9 m above a flat road, beams 24 to 4 deg below the
// horizon 1 deg apart: the rail's face 4.2 m to the right, 0.45-0.8 m above the road, and 16 cm
// square posts behind it (their faces 12 cm behind the rail's) every 4 m, visible below it. A ring
// meets the face lower the farther along the road it looks, so each ring runs off the rail across
// its lower border behind the sensor and onto it across the upper one.
liod::Scan guard_rail_scan() {
  liod::Scan scan;
  const double height = 1.9;
  const double rail_y = -4.2;
  const double rail_bottom = 0.45 - height;
  const double rail_top = 0.8 - height;
  const double post_half = 0.08;
  const double post_y = rail_y - 0.12 - post_half;
  const int rings = 21;
  scan.beam_count = rings;
  for (int ring = 0; ring < rings; ++ring) {
    const double elevation = (-24.0 + ring) * M_PI / 180.0;
    for (int i = 0; i < 1800; ++i) {
      // Each beam fires a little later in the turn than the one below (as the Helios's do).
      const double az = (-180.0 + 0.2 * i + 0.013 * ring) * M_PI / 180.0;
      const Eigen::Vector3d dir(std::cos(elevation) * std::cos(az), std::cos(elevation) * std::sin(az), std::sin(elevation));
      double reach = -height / dir.z();
      if (dir.y() < 0.0) {
        const double t = rail_y / dir.y();
        const double z = t * dir.z();
        if (z >= rail_bottom && z <= rail_top && t < reach) reach = t;
        for (double post_x = -30.0; post_x <= 30.0; post_x += 4.0) {
          // The post's box below the rail (above it, hidden behind the rail or its top).
          const auto enter = box_entry(Eigen::Vector2d::Zero(), dir.head<2>(),
                                       Eigen::Vector2d(post_x - post_half, post_y - post_half),
                                       Eigen::Vector2d(post_x + post_half, post_y + post_half));
          if (enter && *enter < reach && *enter * dir.z() <= rail_bottom) reach = *enter;
        }
      }
      liod::LidarPoint p;
      p.x = static_cast<float>(reach * dir.x());
      p.y = static_cast<float>(reach * dir.y());
      p.z = static_cast<float>(reach * dir.z());
      p.ring = static_cast<std::uint16_t>(ring);
      p.time = static_cast<float>(i * 55.56e-6);
      scan.points.push_back(p);
    }
  }
  std::stable_sort(scan.points.begin(), scan.points.end(),
                   [](const liod::LidarPoint& a, const liod::LidarPoint& b) { return a.time < b.time; });
  scan.end_time = scan.points.back().time;
  return scan;
}

TEST(CurvatureFeatures, ARingRunningOffARailAcrossItsBorderIsNoEdge) {
  // Where a ring crosses the rail's lower or upper border moves along the rail with the sensor's
  // pitch: those edges go, the posts' stay.
  const liod::Scan scan = guard_rail_scan();
  auto count = [&](double tolerance) {
    liod::FeatureParams params;
    params.crossing_edge_tolerance_m = tolerance;
    liod::FeatureExtractor extractor(params);
    liod::ScanFeatures features;
    extractor.extract(scan, features);
    std::pair<int, int> on_rail_and_posts{0, 0};
    for (const std::uint32_t e : features.edges) {
      const auto& p = scan.points[e];
      if (std::abs(p.y + 4.2F) < 1e-3F) ++on_rail_and_posts.first;
      if (p.y < -4.3F && p.y > -4.5F && p.z > -1.9F + 0.01F) ++on_rail_and_posts.second;
    }
    return on_rail_and_posts;
  };
  const auto [rail_kept, posts_kept] = count(0.0);
  const auto [rail_dropped, posts] = count(0.05);
  EXPECT_GE(rail_kept, 4) << "the rail's border crossings are edges without the test";
  EXPECT_EQ(rail_dropped, 0);
  EXPECT_GE(posts, 4);
  EXPECT_EQ(posts, posts_kept);
}

}  // namespace
