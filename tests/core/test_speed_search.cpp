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

// Guardrails 4 m either side of a sensor 1.8 m above the road at `x`, as 16 rings see them:
// each ring crosses a rail's band (0.3-0.8 m above the road) only over a stretch of road fixed
// relative to the sensor. And a post every 25 m beside the right-hand rail, from the road up to 1 m.
std::vector<Eigen::Vector3d> rails_from(double x, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Vector3d> pts;
  auto hit = [&](double along, double side, double height) {
    pts.emplace_back(along + noise(rng), side + noise(rng), height - 1.8);
  };
  for (int ring = 0; ring < 16; ++ring) {
    const double slope = std::tan((-16.0 + ring) * M_PI / 180.0);
    for (int k = 1; k < 1800; ++k) {
      const double azimuth = k * M_PI / 1800.0;  // left of the sensor, then mirrored
      const double range = 4.0 / std::sin(azimuth);
      const double height = 1.8 + range * slope;
      if (range > 60.0) continue;
      if (height >= 0.3 && height <= 0.8) {
        hit(range * std::cos(azimuth), 4.0, height);
        hit(range * std::cos(azimuth), -4.0, height);
      }
      for (double post = -50.0; post <= 50.0; post += 25.0) {
        const double along = post - x;
        const double post_range = std::hypot(along, 4.05);
        const double post_height = 1.8 + post_range * slope;
        if (std::abs(range * std::cos(azimuth) - along) < 0.01 && post_height >= 0.0 && post_height <= 1.0) {
          hit(along, -4.05, post_height);
        }
      }
    }
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

// The displacement along x (-1 to 5 m, 1 cm resolution) under which b's footprint lands best on a's.
double best_displacement(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  liod::GridSearchParams p;
  p.min = -1.0;
  p.max = 5.0;
  p.coarse_step = 0.05;
  p.fine_step = 0.01;
  const liod::FootprintOverlap overlap(a, 0.12);
  return liod::grid_search([&](double d) { return overlap.score(shifted(b, d)); }, p).value;
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

// The rolling start's coarse grid of speed hypotheses (-10 to 50 m/s every 0.5), and a score's
// values over it.
struct SpeedGrid {
  liod::GridSearchParams params{-10.0, 50.0, 0.5, 0.1};
  std::vector<double> hypotheses = liod::coarse_grid(params);
  template <typename Score>
  std::vector<double> scores_of(Score score) const {
    std::vector<double> out;
    for (double x : hypotheses) out.push_back(score(x));
    return out;
  }
  std::size_t index_of(double x) const {
    return static_cast<std::size_t>(std::lround((x - params.min) / params.coarse_step));
  }
};

TEST(GridSearch, ASeparatePeakBesideAStandstillIsFoundOnlyWhereItPeaksOnItsOwn) {
  const SpeedGrid grid;
  const std::vector<double>& hypotheses = grid.hypotheses;
  auto scores_of = [&](auto score) { return grid.scores_of(score); };
  auto standstill = [](double x, double width) { return std::exp(-x * x / (width * width)); };
  // Rail faces fixed in the sensor's frame score a standstill; the moving car's structure peaks
  // at its true speed, 13 m/s, with 85 % of it.
  const auto moving = scores_of([&](double x) { return standstill(x, 1.5) + 0.85 * std::exp(-std::pow(x - 13.0, 2)); });
  const auto peak = liod::separate_peak(hypotheses, moving, 3.0, 0.5);
  ASSERT_TRUE(peak.has_value());
  EXPECT_DOUBLE_EQ(hypotheses[*peak], 13.0);
  // At rest the score falls off on both sides; its best beyond 3 m/s is the shoulder, no peak,
  // however wide the standstill's peak (a tunnel's walls).
  EXPECT_FALSE(liod::separate_peak(hypotheses, scores_of([&](double x) { return standstill(x, 1.5); }), 3.0, 0.5));
  EXPECT_FALSE(liod::separate_peak(hypotheses, scores_of([&](double x) { return standstill(x, 15.0); }), 3.0, 0.1));
  // A bump of a fifth of the standstill's (aliased posts) is not enough.
  const auto bump = scores_of([&](double x) { return standstill(x, 1.5) + 0.2 * std::exp(-std::pow(x - 40.0, 2)); });
  EXPECT_FALSE(liod::separate_peak(hypotheses, bump, 3.0, 0.5));
  EXPECT_TRUE(liod::separate_peak(hypotheses, bump, 3.0, 0.1));
}

TEST(GridSearch, ASpeedStandsClearOnlyWhenItLeadsItsAliasesAndPeaksInsideTheGrid) {
  const SpeedGrid grid;
  const std::vector<double>& hypotheses = grid.hypotheses;
  auto scores_of = [&](auto score) { return grid.scores_of(score); };
  auto peak = [](double x, double at) { return std::exp(-std::pow(x - at, 2)); };
  auto index_of = [&](double x) { return grid.index_of(x); };
  // Posts 4 m apart: the true 15 m/s and its alias at -5 m/s, 4 m in two scans (highway seed 19's
  // evidence at its sixth scan, 62 against 53; 256 against 199 two seconds on).
  const auto close = scores_of([&](double x) { return 62.0 * peak(x, 15.0) + 53.0 * peak(x, -5.0); });
  EXPECT_FALSE(liod::stands_clear_of_aliases(hypotheses, close, index_of(15.0), 2.0, 1.3));
  const auto clear = scores_of([&](double x) { return 256.0 * peak(x, 15.0) + 190.0 * peak(x, -5.0); });
  EXPECT_TRUE(liod::stands_clear_of_aliases(hypotheses, clear, index_of(15.0), 2.0, 1.3));
  // The peak's own shoulders are not rivals, however wide it is.
  const auto wide = scores_of([&](double x) { return std::exp(-std::pow((x - 15.0) / 6.0, 2)); });
  EXPECT_TRUE(liod::stands_clear_of_aliases(hypotheses, wide, index_of(15.0), 2.0, 1.3));
  // A score still rising at the grid's end peaks beyond it: no speed to take there.
  const auto rising = scores_of([&](double x) { return 25.0 * peak(x, 52.0) + 16.0 * peak(x, 15.0); });
  EXPECT_FALSE(liod::stands_clear_of_aliases(hypotheses, rising, hypotheses.size() - 1, 2.0, 1.3));
}

TEST(GridSearch, RingsPullToStandstillButStructureFindsTheMotion) {
  // The second view is 1.5 m further along (15 m/s over 0.1 s). Hypotheses: the displacement.
  const auto first = sparse_road_from(0.0, 1);
  const auto second = sparse_road_from(1.5, 2);
  // All points: the rings, identical in both views, win at zero motion.
  EXPECT_NEAR(best_displacement(first, second), 0.0, 0.05);
  // Vertical structure only: the posts decide.
  const liod::VerticalStructureParams params;
  EXPECT_NEAR(best_displacement(selected(first, liod::vertical_structure(first, params)),
                     selected(second, liod::vertical_structure(second, params))),
              1.5, 0.03);
}

TEST(OffAlongTrackLines, DropsARailAlongTheTrackAndKeepsPostsAndCrossingWalls) {
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.0; x < 2.0; x += 0.05) pts.emplace_back(x, 4.0, 0.5);  // rail along x
  const std::size_t rail = pts.size();
  for (int k = 0; k < 5; ++k) pts.emplace_back(10.0 + 0.01 * k, 4.0, 0.2 * k);  // a post
  const std::size_t post = pts.size();
  for (double y = -1.0; y < 1.0; y += 0.05) pts.emplace_back(20.0, y, 1.0);  // a wall across the road
  const auto kept = liod::off_along_track_lines(pts, {1.0, 0.0}, liod::AlongTrackLineParams{});
  std::size_t rails = 0;
  std::size_t others = 0;
  for (const auto i : kept) (i < rail ? rails : others)++;
  EXPECT_EQ(rails, 0U);
  EXPECT_EQ(others, pts.size() - rail);
  // Driving along y instead, the wall is the rail.
  const auto across = liod::off_along_track_lines(pts, {0.0, 1.0}, liod::AlongTrackLineParams{});
  EXPECT_EQ(across.size(), post);
}

TEST(OffAlongTrackLines, AGuardrailsOwnPostGoesWithTheRail) {
  // What the search without the lines gives up (why a pair that finds a moving speed keeps them):
  // a post 15 cm behind the rail is part of the rail's line in the footprint.
  std::vector<Eigen::Vector3d> pts;
  for (double x = -2.0; x < 2.0; x += 0.05) pts.emplace_back(x, 4.0, 0.5);
  for (int k = 0; k < 5; ++k) pts.emplace_back(0.0, 4.15, 0.2 * k);
  EXPECT_TRUE(liod::off_along_track_lines(pts, {1.0, 0.0}, liod::AlongTrackLineParams{}).empty());
}

TEST(GridSearch, RailsSampledByRingsVoteForAStandstillThatTheirLinesDoNot) {
  // 1.2 m further along in the second view (12 m/s over 0.1 s).
  const liod::VerticalStructureParams params;
  auto structure = [&](const std::vector<Eigen::Vector3d>& pts) { return selected(pts, liod::vertical_structure(pts, params)); };
  const auto first = structure(rails_from(0.0, 1));
  const auto second = structure(rails_from(1.2, 2));
  EXPECT_NEAR(best_displacement(first, second), 0.0, 0.05);
  auto off_lines = [](const std::vector<Eigen::Vector3d>& pts) {
    return selected(pts, liod::off_along_track_lines(pts, {1.0, 0.0}, liod::AlongTrackLineParams{}));
  };
  EXPECT_NEAR(best_displacement(off_lines(first), off_lines(second)), 1.2, 0.03);
}

}  // namespace
