#include <gtest/gtest.h>

#include <cmath>

#include "liod/curvature_features.hpp"

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

}  // namespace
