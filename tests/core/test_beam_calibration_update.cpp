#include "beam_direction.hpp"
#include "liod/angles.hpp"
#include "liod/beam_calibration_update.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "liod/so3.hpp"

namespace liod {
namespace {

// A car on flat ground (world z = 0), turned 40 deg, its level LiDAR 1.8 m above the ground
// (1 m above the IMU, which rides 0.8 m up). The map is the ground as beams with their true
// angles build it: a 0.3 m grid ahead of the car.
struct FlatGround {
  NavState state;
  Pose lidar_to_imu;
  LocalMap map{1.0, 20, 0.2};
  double height = 1.8;

  FlatGround() {
    state.position = Eigen::Vector3d(100.0, 20.0, 0.8);
    state.rotation = so3::exp(Eigen::Vector3d(0.0, 0.0, 40.0 * kDegToRad));
    lidar_to_imu.translation = Eigen::Vector3d(0.5, 0.0, 1.0);
    std::vector<Eigen::Vector3d> ground;
    for (double x = 4.0; x < 56.0; x += 0.3) {
      for (double y = -36.0; y < 36.0; y += 0.3) ground.push_back(to_world({x, y, -height}));
    }
    map.add(ground, 0);
  }
  Eigen::Vector3d to_world(const Eigen::Vector3d& lidar) const { return state.to_world(lidar_to_imu * lidar); }
};

// One scan of the ground by beams at `published` elevations whose true elevations are
// published + error: each return is the true range along the published direction, corrected by
// the calibration as deskew_features does.
DeskewedFeatures ground_scan(const FlatGround& g, const std::vector<double>& published,
                             const std::vector<double>& error, const BeamCalibration& calibration, int scan) {
  DeskewedFeatures f;
  for (std::size_t k = 0; k < published.size(); ++k) {
    const auto ring = static_cast<std::uint16_t>(k);
    const double range = g.height / std::sin(-(published[k] + error[k]));
    for (int a = 0; a <= 240; ++a) {
      const double azimuth = (-30.0 + 0.25 * a + 0.01 * (scan % 25)) * kDegToRad;
      const Eigen::Vector3d lidar = calibration.correct(range * test::beam_direction(published[k], azimuth), ring);
      f.map_planes.push_back(g.lidar_to_imu * lidar);
      f.map_plane_sources.push_back({ring, lidar});
    }
  }
  f.planes = f.map_planes;
  return f;
}

// Beam 3 (at -4 deg, its ground 25.7 m away) points 0.01 deg above its published elevation, so its
// ground ring lies 4.5 mm too low; beam 0 (at -15 deg) is off as much, but its ground is 6.7 m away,
// nearer than the calibration looks (there an offset moves a point by a millimetre). Over repeated
// scans beam 3's offset goes to the truth less the part proportional to the elevation that a pose
// cannot tell from a height (the gauge the calibration removes), and its ring onto the ground.
TEST(UpdateBeamCalibration, AFarBeamsElevationOffsetMovesTowardsTheTruth) {
  const FlatGround g;
  const std::vector<double> published = {-15.0 * kDegToRad, -8.0 * kDegToRad, -6.0 * kDegToRad,
                                         -4.0 * kDegToRad,  -3.0 * kDegToRad, -2.0 * kDegToRad};
  const double delta = 0.01 * kDegToRad;
  const std::vector<double> error = {delta, 0.0, 0.0, delta, 0.0, 0.0};
  CorrespondenceParams correspondence;
  correspondence.max_distance_m = 1.0;

  // The truth (+delta on beam 3: the correction raises a beam's points by its offset) less its
  // least-squares fit b * elevation over the beams the calibration learns (1 to 5).
  double ee = 0.0;
  for (std::size_t k = 1; k < published.size(); ++k) ee += published[k] * published[k];
  const double slope = published[3] * delta / ee;
  auto expected = [&](std::size_t k) { return (k == 3 ? delta : 0.0) - slope * published[k]; };

  // How far beam 3's corrected returns lie off the ground (largest over the ring).
  auto ring_3_off_ground = [&](const BeamCalibration& c) {
    double worst = 0.0;
    const DeskewedFeatures f = ground_scan(g, published, error, c, 0);
    for (std::size_t i = 0; i < f.map_planes.size(); ++i) {
      if (f.map_plane_sources[i].ring == 3) worst = std::max(worst, std::abs(g.state.to_world(f.map_planes[i]).z()));
    }
    return worst;
  };

  BeamCalibration calibration(published.size());
  const double off_before = ring_3_off_ground(calibration);
  EXPECT_NEAR(off_before, 25.7 * delta, 0.2e-3) << "range x offset";
  std::vector<double> distance_to_expected;
  for (int scan = 0; scan < 150; ++scan) {
    update_beam_calibration(calibration, ground_scan(g, published, error, calibration, scan), g.state, g.lidar_to_imu,
                            g.map, correspondence, 0.03);
    distance_to_expected.push_back(std::abs(calibration.offset_rad(3) - expected(3)));
  }
  EXPECT_LT(distance_to_expected[9], expected(3)) << "moving from zero";
  EXPECT_LT(distance_to_expected[39], distance_to_expected[9]);
  EXPECT_LT(distance_to_expected.back(), distance_to_expected[39]);
  EXPECT_LT(distance_to_expected.back(), 0.1 * expected(3))
      << "offset " << calibration.offset_rad(3) / kDegToRad << " deg, expected " << expected(3) / kDegToRad;
  for (std::size_t k = 1; k < published.size(); ++k) {
    EXPECT_NEAR(calibration.offset_rad(static_cast<std::uint16_t>(k)), expected(k), 0.1 * delta) << "beam " << k;
  }
  EXPECT_EQ(calibration.offset_rad(0), 0.0) << "the near beam is not learned";
  EXPECT_LT(ring_3_off_ground(calibration), 0.3 * off_before);
}

// A scan that sees nothing the map has (a map of another place) teaches no beam anything.
TEST(UpdateBeamCalibration, NoMapNoCorrection) {
  const FlatGround g;
  const std::vector<double> published = {-8.0 * kDegToRad, -4.0 * kDegToRad};
  const std::vector<double> error = {0.0, 0.01 * kDegToRad};
  LocalMap elsewhere(1.0, 20, 0.2);
  elsewhere.add({Eigen::Vector3d(-500.0, 0.0, 0.0), Eigen::Vector3d(-500.0, 0.5, 0.0)}, 0);
  BeamCalibration calibration(published.size());
  for (int scan = 0; scan < 20; ++scan) {
    update_beam_calibration(calibration, ground_scan(g, published, error, calibration, scan), g.state, g.lidar_to_imu,
                            elsewhere, CorrespondenceParams{}, 0.03);
  }
  EXPECT_EQ(calibration.offset_rad(0), 0.0);
  EXPECT_EQ(calibration.offset_rad(1), 0.0);
}

}  // namespace
}  // namespace liod
