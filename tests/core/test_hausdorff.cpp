#include <gtest/gtest.h>

#include <random>

#include "liod/hausdorff.hpp"

namespace {

double brute_directed(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  double worst = 0.0;
  for (const auto& p : a) {
    double best = 1e300;
    for (const auto& q : b) best = std::min(best, (p - q).norm());
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(Hausdorff, MatchesBruteForceBelowTheCap) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 20.0);
  std::normal_distribution<double> jitter(0.0, 0.1);
  std::vector<Eigen::Vector3d> a;
  std::vector<Eigen::Vector3d> b;
  for (int i = 0; i < 800; ++i) {
    Eigen::Vector3d p(u(rng), u(rng), u(rng) * 0.1);
    a.push_back(p);
    b.push_back(p + Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng)));
  }
  const double expected = std::max(brute_directed(a, b), brute_directed(b, a));
  ASSERT_LT(expected, 2.0);
  EXPECT_NEAR(liod::hausdorff_distance(a, b, 2.0), expected, 1e-12);
}

TEST(Hausdorff, IsAsymmetricInItsDirectedForm) {
  const std::vector<Eigen::Vector3d> a{{0, 0, 0}, {1, 0, 0}};
  const std::vector<Eigen::Vector3d> b{{0, 0, 0}, {1, 0, 0}, {1, 0.8, 0}};
  EXPECT_NEAR(liod::directed_hausdorff(a, b, 5.0), 0.0, 1e-12);
  EXPECT_NEAR(liod::directed_hausdorff(b, a, 5.0), 0.8, 1e-12);
  EXPECT_NEAR(liod::hausdorff_distance(a, b, 5.0), 0.8, 1e-12);
}

TEST(Hausdorff, SaturatesAtTheCap) {
  const std::vector<Eigen::Vector3d> a{{0, 0, 0}};
  const std::vector<Eigen::Vector3d> b{{10, 0, 0}};
  EXPECT_DOUBLE_EQ(liod::hausdorff_distance(a, b, 2.0), 2.0);
  EXPECT_DOUBLE_EQ(liod::hausdorff_distance(a, {}, 2.0), 2.0);
}

}  // namespace
