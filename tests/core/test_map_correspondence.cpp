#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "liod/map_correspondence.hpp"
#include "ray_box.hpp"

namespace {

// A query beyond the end of a narrow strip of noisy map points (as ahead of the rings a keyframe
// left on the ground): the fitted plane's tilt, not the query's own noise, dominates the residual.
struct StripTrial {
  double residual;
  double variance_scale;
};

StripTrial strip_trial(std::mt19937& rng, double sigma, double query_x, bool fit_uncertainty) {
  std::normal_distribution<double> noise(0.0, sigma);
  liod::LocalMap map(1.0, liod::LocalMap::kMaxPointsPerVoxel, 0.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 4; ++i) {
    for (int row = 0; row < 2; ++row) points.emplace_back(0.1 + 0.15 * i, 0.1 + 0.25 * row, 0.5 + noise(rng));
  }
  map.add(points, 0);
  liod::LocalMap::NeighbourSearch search(map);
  liod::CorrespondenceParams params;
  params.neighbours = 8;
  params.max_distance_m = 1.0;
  params.max_plane_thickness_m = 1.0;  // the trial measures the fit, not the thickness test
  params.fit_uncertainty = fit_uncertainty;
  const Eigen::Vector3d query(query_x, 0.22, 0.5);  // on the true plane z = 0.5
  const auto plane = liod::plane_correspondence(search, query, params);
  if (!plane) return {std::nan(""), std::nan("")};
  return {plane->evaluate(query), plane->variance_scale};
}

TEST(MapCorrespondence, PlaneVarianceMatchesTheFitsScatter) {
  std::mt19937 rng(7);
  const double sigma = 0.01;
  for (const double query_x : {0.3, 0.9}) {
    double sum_r2 = 0.0;
    double sum_predicted = 0.0;
    int n = 0;
    for (int trial = 0; trial < 4000; ++trial) {
      const StripTrial t = strip_trial(rng, sigma, query_x, true);
      ASSERT_TRUE(std::isfinite(t.residual));
      sum_r2 += t.residual * t.residual;
      sum_predicted += (t.variance_scale - 1.0) * sigma * sigma;  // minus the query's own noise (exact here)
      ++n;
    }
    // The fitted plane's scatter at the query, against what variance_scale predicts for it.
    EXPECT_NEAR(sum_r2 / sum_predicted, 1.0, 0.15) << "query at x = " << query_x;
  }
  // Beyond the strip's end the tilt matters: several times the variance at its middle.
  std::mt19937 again(8);
  const double inside = strip_trial(again, sigma, 0.3, true).variance_scale;
  const double beyond = strip_trial(again, sigma, 0.9, true).variance_scale;
  EXPECT_LT(inside, 1.5);
  EXPECT_GT(beyond, 3.0 * (inside - 1.0) + 1.0);
  EXPECT_EQ(strip_trial(again, sigma, 0.9, false).variance_scale, 1.0);
}

TEST(MapCorrespondence, LineVarianceGrowsAlongTheLine) {
  liod::LocalMap map(1.0, liod::LocalMap::kMaxPointsPerVoxel, 0.0);
  std::vector<Eigen::Vector3d> pole;
  for (int i = 0; i < 8; ++i) pole.emplace_back(0.5 + 0.002 * (i % 2), 0.5, 0.1 + 0.05 * i);  // a vertical edge
  map.add(pole, 0);
  liod::CorrespondenceParams params;
  params.neighbours = 8;
  params.max_distance_m = 1.0;
  liod::LocalMap::NeighbourSearch search(map);
  const auto level = liod::line_correspondence(search, {0.6, 0.5, 0.275}, params);   // beside its middle
  const auto above = liod::line_correspondence(search, {0.6, 0.5, 0.9}, params);     // past its top
  ASSERT_TRUE(level && above);
  EXPECT_NEAR(level->evaluate({0.6, 0.5, 0.275}), 0.1, 0.005);
  EXPECT_LT(level->variance_scale, 1.2);
  EXPECT_GT(above->variance_scale, 2.0);
}

// A post seen from the LiDAR: a point displaced across the ray (where the beam grazed the post)
// moves the point-to-line residual, not the residual along the ray; a range error moves both.
TEST(MapCorrespondence, AlongTheRayOnlyTheRangeCounts) {
  liod::LocalMap map(1.0, liod::LocalMap::kMaxPointsPerVoxel, 0.0);
  std::vector<Eigen::Vector3d> post;
  for (int i = 0; i < 8; ++i) post.emplace_back(5.5 + 0.002 * (i % 2), 0.5, 0.1 + 0.1 * i);
  map.add(post, 0);
  liod::CorrespondenceParams params;
  params.neighbours = 8;
  params.max_distance_m = 1.0;
  const Eigen::Vector3d sensor(0.5, 0.5, 0.4);
  const Eigen::Vector3d across(5.501, 0.55, 0.4);  // 5 cm beside the post, seen from the sensor
  const Eigen::Vector3d behind(5.551, 0.5, 0.4);   // 5 cm too far
  liod::LocalMap::NeighbourSearch search(map);
  const auto shortest = liod::line_correspondence(search, across, params);
  const auto ray_across = liod::line_correspondence(search, across, params, &sensor);
  const auto ray_behind = liod::line_correspondence(search, behind, params, &sensor);
  ASSERT_TRUE(shortest && ray_across && ray_behind);
  EXPECT_NEAR(std::abs(shortest->evaluate(across)), 0.05, 0.002);
  EXPECT_LT(std::abs(ray_across->evaluate(across)), 0.002);
  EXPECT_NEAR(ray_behind->evaluate(behind), 0.05, 0.002);
  EXPECT_NEAR(ray_behind->normal.dot(Eigen::Vector3d::UnitX()), 1.0, 1e-3);
}

// A guard-rail post below its rail, as the edge map keeps it: two points one above the other (the
// map's 0.2 m spacing), and the rail's top edge 0.5 m above them, a horizontal line. Too few for
// a fitted line; as a post, an edge point on it gives its range error along the ray.
liod::LocalMap edge_map_of(const std::vector<Eigen::Vector3d>& points) {
  liod::LocalMap map(1.0, liod::LocalMap::kMaxPointsPerVoxel, 0.0);
  map.add(points, 0);
  return map;
}

liod::LocalMap rail_with_post() {
  std::vector<Eigen::Vector3d> points{{5.52, -4.30, 0.10}, {5.56, -4.32, 0.32}};
  for (int i = 0; i < 10; ++i) points.emplace_back(4.0 + 0.3 * i, -4.15, 0.80);
  return edge_map_of(points);
}

const Eigen::Vector3d kRoofSensor(0.0, 0.0, 1.83);  // the LiDAR's origin, 1.83 m above the road

// With depth 0 the map's points are the posts' axes and an edge point is its own axis estimate.
std::optional<liod::LinearResidual> post_at(const liod::LocalMap& map, const Eigen::Vector3d& query,
                                            const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ(),
                                            const Eigen::Vector3d& sensor = kRoofSensor, double depth = 0.0) {
  liod::LocalMap::NeighbourSearch search(map);
  liod::PostParams params;
  params.depth_m = depth;
  return liod::post_correspondence(search, query, up, sensor, params);
}

TEST(MapCorrespondence, TwoPointsOfAShortPostGiveItsRangeAlongTheRay) {
  const liod::LocalMap map = rail_with_post();
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d& sensor = kRoofSensor;
  liod::CorrespondenceParams lines;
  lines.neighbours = 8;
  lines.max_distance_m = 1.0;
  // On the post's axis, 5 cm beyond it along the ray, and 5 cm beside it across the ray.
  const Eigen::Vector3d axis(5.54, -4.31, 0.2);
  const Eigen::Vector3d ray = Eigen::Vector3d(axis.x() - sensor.x(), axis.y() - sensor.y(), 0.0).normalized();
  const Eigen::Vector3d beyond = axis + 0.05 * ray;
  const Eigen::Vector3d beside = axis + 0.05 * up.cross(ray);
  liod::LocalMap::NeighbourSearch search(map);
  EXPECT_FALSE(liod::line_correspondence(search, beyond, lines, &sensor)) << "the post is no fitted line";
  const auto on_axis = post_at(map, axis);
  const auto far = post_at(map, beyond);
  const auto across = post_at(map, beside);
  ASSERT_TRUE(on_axis && far && across);
  EXPECT_NEAR(on_axis->evaluate(axis), 0.0, 1e-3);
  EXPECT_NEAR(far->evaluate(beyond), 0.05, 1e-3);
  EXPECT_NEAR(std::abs(across->evaluate(beside)), 0.0, 2e-3);
  EXPECT_NEAR(far->normal.dot(up), 0.0, 1e-12);  // a range error in the horizontal only
  EXPECT_NEAR(far->normal.dot(ray), 1.0, 1e-9);
}

// Where the horizontal ray from `sensor` towards a square post's axis meets its near side, at
// height z (the post stands at `centre`, half-width `half`, sides along x and y).
Eigen::Vector3d near_side_hit(const Eigen::Vector3d& sensor, const Eigen::Vector2d& centre, double half, double z) {
  const Eigen::Vector2d from = sensor.head<2>();
  const Eigen::Vector2d d = (centre - from).normalized();
  const auto enter = liod::test::box_entry(from, d, centre.array() - half, centre.array() + half);
  const Eigen::Vector2d hit = from + enter.value() * d;
  return {hit.x(), hit.y(), z};
}

TEST(MapCorrespondence, APostsAxisDoesNotMoveWithTheSideTheRingsMeet) {
  // A guard-rail post 16 cm square, 4.3 m right of the lane. Three keyframes on the approach
  // (20, 15 and 10 m before it) saw the face towards them, each on one ring; the scan sees it from 12 m past it,
  // its back face, at the true pose.
  const Eigen::Vector2d post(30.0, -4.3);
  const double half = 0.08;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  auto sensor_at = [](double x) { return Eigen::Vector3d(x, 0.0, 1.83); };
  auto map_of = [&](double depth) {
    std::vector<Eigen::Vector3d> axes;
    for (const double x : {10.0, 15.0, 20.0}) {  // one ring each, at 0.1, 0.3 and 0.5 m
      const std::vector<Eigen::Vector3d> edges{near_side_hit(sensor_at(x), post, half, 0.04 * x - 0.3)};
      const auto seen = liod::post_axes(edges, sensor_at(x), up, depth);
      axes.insert(axes.end(), seen.begin(), seen.end());
    }
    return edge_map_of(axes);
  };
  const Eigen::Vector3d sensor = sensor_at(42.0);
  const Eigen::Vector3d query = near_side_hit(sensor, post, half, 0.3);
  // The edge points as they are: the back face 16 cm behind the front one, 15 cm along the ray.
  const auto points = post_at(map_of(0.0), query, up, sensor, 0.0);
  // Each moved half the post's depth along its own ray: both near the axis, within 1.5 cm.
  const auto axes = post_at(map_of(0.08), query, up, sensor, 0.08);
  ASSERT_TRUE(points && axes);
  EXPECT_GT(std::abs(points->evaluate(query)), 0.12);
  EXPECT_LT(std::abs(axes->evaluate(query)), 0.015);
  // The residual is still the range along the ray: 5 cm farther reads 5 cm.
  const Eigen::Vector3d ray = Eigen::Vector3d(query.x() - sensor.x(), query.y() - sensor.y(), 0.0).normalized();
  EXPECT_NEAR(axes->evaluate(query + 0.05 * ray) - axes->evaluate(query), 0.05, 1e-9);
}

TEST(MapCorrespondence, HorizontalEdgesAndScatteredPointsAreNoPost) {
  const liod::LocalMap map = rail_with_post();
  // On the rail's top edge: its nearest points lie side by side, not one above the other.
  EXPECT_FALSE(post_at(map, {6.7, -4.15, 0.80}));
  // Two points 0.3 m apart across the vertical: no post between them.
  EXPECT_FALSE(post_at(edge_map_of({{2.5, 2.5, 0.3}, {2.8, 2.5, 0.5}}), {2.65, 2.5, 0.4}));
  // A single point: nothing to tell a post from a speck.
  EXPECT_FALSE(post_at(edge_map_of({{2.5, 2.5, 0.3}}), {2.5, 2.5, 0.35}));
  // The same two post points seen with the world tilted 90 deg (up along x) lie side by side.
  EXPECT_FALSE(post_at(map, {5.54, -4.31, 0.2}, Eigen::Vector3d::UnitX()));
}

// A plane's eight map points centred on `centre` (4 x 2 along u and v, 0.2 / 0.3 m apart): every
// query near it has the same neighbours, so the fitted plane's centroid is `centre`.
liod::LocalMap patch_map(const Eigen::Vector3d& centre, const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
  liod::LocalMap map(1.0, liod::LocalMap::kMaxPointsPerVoxel, 0.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 2; ++j) points.push_back(centre + 0.2 * (i - 1.5) * u + 0.3 * (j - 0.5) * v);
  }
  map.add(points, 0);
  return map;
}

TEST(MapCorrespondence, PlanesBlindAlongTheTrackLocateAcrossItOnly) {
  liod::CorrespondenceParams params;
  params.neighbours = 8;
  params.max_distance_m = 1.0;
  liod::CorrespondenceParams blind = params;
  blind.blind_along = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  // A wall at 30 degrees to the track (x), as a barrier seen at a slant ahead.
  const Eigen::Vector3d along_wall(std::cos(M_PI / 6), std::sin(M_PI / 6), 0.0);
  const Eigen::Vector3d on_wall(10.0, 4.0, 0.6);
  const liod::LocalMap wall = patch_map(on_wall, along_wall, up);
  liod::LocalMap::NeighbourSearch wall_search(wall);
  const Eigen::Vector3d along_track_step = on_wall + Eigen::Vector3d(0.2, 0.0, 0.0);
  const auto seen = liod::plane_correspondence(wall_search, along_track_step, params);
  const auto blinded = liod::plane_correspondence(wall_search, along_track_step, blind);
  ASSERT_TRUE(seen && blinded);
  EXPECT_NEAR(std::abs(seen->evaluate(along_track_step)), 0.2 * std::sin(M_PI / 6), 1e-6);
  EXPECT_NEAR(blinded->evaluate(along_track_step), 0.0, 1e-6);  // a step along the track is not seen
  EXPECT_NEAR(blinded->normal.norm(), 1.0, 1e-9);
  EXPECT_NEAR(blinded->normal.x(), 0.0, 1e-9);
  const Eigen::Vector3d across_step = on_wall + Eigen::Vector3d(0.0, 0.2, 0.0);
  EXPECT_NEAR(std::abs(blinded->evaluate(across_step)), 0.2, 1e-6);  // one across it is, in full

  // The ground, here rising 5 % along the track, keeps its normal unless blind_ground: at rest its
  // fine pattern holds the position; once rolling it too locates the scan across the track only.
  const Eigen::Vector3d uphill = Eigen::Vector3d(1.0, 0.0, 0.05).normalized();
  const Eigen::Vector3d on_ground(10.0, 0.0, -1.8);
  const liod::LocalMap ground = patch_map(on_ground, uphill, Eigen::Vector3d::UnitY());
  liod::LocalMap::NeighbourSearch ground_search(ground);
  const Eigen::Vector3d ahead = on_ground + Eigen::Vector3d(0.2, 0.0, 0.0);
  const auto ground_seen = liod::plane_correspondence(ground_search, ahead, params);
  const auto ground_kept = liod::plane_correspondence(ground_search, ahead, blind);
  liod::CorrespondenceParams blind_ground = blind;
  blind_ground.blind_ground = true;
  const auto ground_blinded = liod::plane_correspondence(ground_search, ahead, blind_ground);
  ASSERT_TRUE(ground_seen && ground_kept && ground_blinded);
  EXPECT_NEAR(std::abs(ground_seen->evaluate(ahead)), 0.2 * 0.05 / std::hypot(1.0, 0.05), 1e-6);
  EXPECT_NEAR(ground_kept->evaluate(ahead), ground_seen->evaluate(ahead), 1e-12);
  EXPECT_NEAR(ground_blinded->evaluate(ahead), 0.0, 1e-6);
  const Eigen::Vector3d above = on_ground + Eigen::Vector3d(0.0, 0.0, 0.1);
  EXPECT_NEAR(std::abs(ground_blinded->evaluate(above)), 0.1, 1e-6);

  // A wall facing the track would locate nothing else: no residual.
  const liod::LocalMap facing = patch_map(Eigen::Vector3d(20.0, 0.0, 0.6), Eigen::Vector3d::UnitY(), up);
  liod::LocalMap::NeighbourSearch facing_search(facing);
  const Eigen::Vector3d before(19.8, 0.0, 0.6);
  EXPECT_TRUE(liod::plane_correspondence(facing_search, before, params).has_value());
  EXPECT_FALSE(liod::plane_correspondence(facing_search, before, blind).has_value());
}

}  // namespace
