#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "liod/speed_search.hpp"

namespace {

// A sparse road seen by a sensor 1.8 m above the ground at `x`: ground rings that move with the
// sensor (what pulls a registration towards standstill), a rail along the road, and posts every
// 4 m behind it, all in the sensor's frame (z up).
std::vector<Eigen::Vector3d> sparse_road_from(double x, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector3d> pts;
  for (double radius = 4.0; radius < 40.0; radius *= 1.15) {
    for (int k = 0; k < 720; ++k) {
      const double a = k * M_PI / 360.0;
      pts.emplace_back(radius * std::cos(a), radius * std::sin(a), -1.8 + noise(rng));
    }
  }
  for (double along = -40.0; along < 40.0; along += 0.05) {
    for (double h : {0.5, 0.65, 0.8}) pts.emplace_back(along - x, 11.8 + noise(rng), h - 1.8);
  }
  for (double post = -40.0; post < 40.0; post += 4.0) {
    for (double h = 0.0; h < 0.45; h += 0.1) pts.emplace_back(post - x + noise(rng), 11.95, h - 1.8);
  }
  return pts;
}

std::vector<Eigen::Vector3d> selected(const std::vector<Eigen::Vector3d>& points, const std::vector<std::size_t>& idx) {
  std::vector<Eigen::Vector3d> out;
  for (const auto i : idx) out.push_back(points[i]);
  return out;
}

std::vector<Eigen::Vector3d> shifted(std::vector<Eigen::Vector3d> points, double dx) {
  for (auto& p : points) p.x() += dx;
  return points;
}

TEST(VerticalStructure, KeepsPostsAndDropsFlatGround) {
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.0; x < 10.0; x += 0.1) {
    for (double y = 0.0; y < 10.0; y += 0.3) pts.emplace_back(x, y, 0.01 * x);  // a 1 % grade
  }
  const std::size_t ground = pts.size();
  for (int k = 0; k < 10; ++k) pts.emplace_back(5.02, 5.02, 0.1 * k);  // a post on it
  const auto kept = liod::vertical_structure(pts, liod::VerticalStructureParams{});
  ASSERT_FALSE(kept.empty());
  for (const auto i : kept) {
    EXPECT_GE(i, ground);
    EXPECT_GE(pts[i].z(), 0.2);  // the post's foot is ground
  }
  EXPECT_EQ(kept.size(), 8U);  // z = 0.2 .. 0.9
}

TEST(FootprintOverlap, CountsMatchesByHorizontalDistanceOnly) {
  const std::vector<Eigen::Vector3d> reference{{0, 0, 0}, {5, 0, 0}};
  const liod::FootprintOverlap overlap(reference, 0.2);
  EXPECT_DOUBLE_EQ(overlap.score({{0, 0, 3.0}, {5, 0, -2.0}}), 2.0);  // height is ignored
  EXPECT_NEAR(overlap.score({{0.1, 0, 0}}), 0.75, 1e-12);              // 1 - (0.1 / 0.2)^2
  EXPECT_DOUBLE_EQ(overlap.score({{0.3, 0, 0}, {2.5, 0, 0}}), 0.0);
}

TEST(GridSearch, FindsTheGlobalMaximumAmongSideLobes) {
  // A main peak at 14.12 between narrow side lobes every 4 (as posts every 4 m give) at 60 %.
  auto score = [](double x) { return std::exp(-std::pow(x - 14.12, 2)) + 0.6 * std::pow(std::cos(x * M_PI / 4.0), 40); };
  liod::GridSearchParams p;
  p.min = -10.0;
  p.max = 50.0;
  p.coarse_step = 0.5;
  p.fine_step = 0.01;
  const auto found = liod::grid_search(score, p);
  EXPECT_NEAR(found.value, 14.12, 0.01);
}

TEST(GridSearch, RingsPullToStandstillButStructureFindsTheMotion) {
  // The second view is 1.5 m further along (15 m/s over 0.1 s). Hypotheses: the displacement.
  const auto first = sparse_road_from(0.0, 1);
  const auto second = sparse_road_from(1.5, 2);
  liod::GridSearchParams p;
  p.min = -1.0;
  p.max = 5.0;
  p.coarse_step = 0.05;
  p.fine_step = 0.01;
  auto search = [&](const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
    const liod::FootprintOverlap overlap(a, 0.12);
    return liod::grid_search([&](double d) { return overlap.score(shifted(b, d)); }, p).value;
  };
  // All points: the rings, identical in both views, win at zero motion.
  EXPECT_NEAR(search(first, second), 0.0, 0.05);
  // Vertical structure only: the posts decide.
  const liod::VerticalStructureParams params;
  EXPECT_NEAR(search(selected(first, liod::vertical_structure(first, params)),
                     selected(second, liod::vertical_structure(second, params))),
              1.5, 0.03);
}

}  // namespace
