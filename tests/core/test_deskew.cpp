#include "liod/angles.hpp"
#include "liod/deskew.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <vector>

#include "liod/so3.hpp"

namespace liod {
namespace {

double rotation_error(const Eigen::Quaterniond& a, const Eigen::Matrix3d& b) {
  return so3::log(a.toRotationMatrix().transpose() * b).norm();
}

// Intervals from samples every 5 ms over [from, to] that all read `gyro` and `accel`.
std::vector<ImuInterval> constant_intervals(double from, double to, const Eigen::Vector3d& gyro,
                                            const Eigen::Vector3d& accel) {
  std::deque<ImuSample> samples;
  for (double t = from - 0.01; t < to + 0.01; t += 0.005) samples.push_back({t, gyro, accel});
  return imu_intervals(samples, from, to);
}

// A car heading 36.87 deg left of the world x axis at 10 m/s (world velocity (8, 6, 0)), level,
// its IMU reading only gravity's reaction and the biases: over a 0.1 s sweep it was 1 m behind its
// end pose along its own forward axis at the sweep's start, and half that at the middle.
TEST(DeskewTrajectory, ImuAtConstantVelocityGivesTheDistanceTravelledBehindTheEnd) {
  NavState start;
  start.time = 10.0;
  start.rotation = so3::exp(Eigen::Vector3d(0, 0, std::atan2(6.0, 8.0)));
  start.position = Eigen::Vector3d(3.0, 4.0, 0.5);
  start.velocity = Eigen::Vector3d(8.0, 6.0, 0.0);
  start.gyro_bias = Eigen::Vector3d(0.002, -0.001, 0.003);
  start.accel_bias = Eigen::Vector3d(0.05, 0.02, -0.04);
  NavState end = start;
  end.time = 10.1;
  end.position = start.position + start.velocity * 0.1;
  const auto intervals =
      constant_intervals(10.0, 10.1, start.gyro_bias, Eigen::Vector3d(0, 0, 9.80665) + start.accel_bias);

  const PoseTable relative = deskew_trajectory(DeskewMode::kImu, 10.0, 10.1, start, end, intervals, {});
  EXPECT_LT((relative.at(10.0).translation - Eigen::Vector3d(-1.0, 0.0, 0.0)).norm(), 1e-9);
  EXPECT_LT(rotation_error(relative.at(10.0).rotation, Eigen::Matrix3d::Identity()), 1e-9);
  EXPECT_LT((relative.at(10.05).translation - Eigen::Vector3d(-0.5, 0.0, 0.0)).norm(), 1e-9);
  EXPECT_LT(relative.at(10.1).translation.norm(), 1e-9);
}

// Turning on the spot at 0.5 rad/s: at the sweep's start the body was turned 0.05 rad right of
// its end heading, and stood where it ends.
TEST(DeskewTrajectory, ImuTurningGivesTheRotationBehindTheEnd) {
  NavState start;
  start.time = 3.0;
  start.rotation = so3::exp(Eigen::Vector3d(0, 0, 1.0));
  NavState end = start;
  end.time = 3.1;
  end.rotation = start.rotation * so3::exp(Eigen::Vector3d(0, 0, 0.05));
  const auto intervals =
      constant_intervals(3.0, 3.1, Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d(0, 0, 9.80665));
  const PoseTable relative = deskew_trajectory(DeskewMode::kImu, 3.0, 3.1, start, end, intervals, {});
  EXPECT_LT(rotation_error(relative.at(3.0).rotation, so3::exp(Eigen::Vector3d(0, 0, -0.05))), 1e-9);
  EXPECT_LT(rotation_error(relative.at(3.05).rotation, so3::exp(Eigen::Vector3d(0, 0, -0.025))), 1e-6);
  EXPECT_LT(relative.at(3.0).translation.norm(), 1e-9);
}

// Constant velocity (LOAM): the end state's velocity, in the body frame, and the given rate taken
// back through the sweep; the IMU intervals are not read.
TEST(DeskewTrajectory, ConstantVelocityTakesTheEndVelocityAndRateBack) {
  NavState end;
  end.rotation = so3::exp(Eigen::Vector3d(0, 0, M_PI / 2));  // facing world y
  end.velocity = Eigen::Vector3d(0.0, 10.0, 0.0);             // forward at 10 m/s
  const Eigen::Vector3d rate(0.0, 0.0, 0.3);
  const PoseTable relative = deskew_trajectory(DeskewMode::kConstantVelocity, 5.0, 5.1, NavState{}, end, {}, rate);
  EXPECT_LT((relative.at(5.0).translation - Eigen::Vector3d(-1.0, 0.0, 0.0)).norm(), 1e-9);
  EXPECT_LT(rotation_error(relative.at(5.0).rotation, so3::exp(-rate * 0.1)), 1e-9);
  EXPECT_LT((relative.at(5.05).translation - Eigen::Vector3d(-0.5, 0.0, 0.0)).norm(), 1e-9);
  EXPECT_LT(relative.at(5.1).translation.norm(), 1e-12);
}

TEST(DeskewTrajectory, NoneLeavesEveryPointWhereItWasMeasured) {
  NavState end;
  end.velocity = Eigen::Vector3d(20.0, 0.0, 0.0);
  const PoseTable relative =
      deskew_trajectory(DeskewMode::kNone, 0.0, 0.1, NavState{}, end, {}, Eigen::Vector3d(0, 0, 1));
  for (const double t : {-1.0, 0.0, 0.05, 0.1, 1.0}) {
    EXPECT_EQ(relative.at(t).translation, Eigen::Vector3d::Zero());
    EXPECT_LT(rotation_error(relative.at(t).rotation, Eigen::Matrix3d::Identity()), 1e-15);
  }
}

// A car at 15 m/s drives straight at a wall 30 m ahead of where its sweep ends (world x = 30, the
// body at the origin at the sweep's end), its LiDAR mounted tilted and offset from the IMU. Each
// point is measured from where the LiDAR was at its own time, so without deskew the wall spreads
// over the 1.5 m the car covered; deskewed, every plane and edge point lies on x = 30 again.
struct WallScan {
  Scan scan;
  ScanFeatures features;
  Pose lidar_to_imu;
};

WallScan wall_scan() {
  WallScan w;
  w.lidar_to_imu.rotation = Eigen::Quaterniond(so3::exp(Eigen::Vector3d(1.0 * kDegToRad, -2.0 * kDegToRad, 3.0 * kDegToRad)));
  w.lidar_to_imu.translation = Eigen::Vector3d(0.8, 0.1, 1.4);
  const Pose imu_to_lidar = w.lidar_to_imu.inverse();
  auto add_point = [&](const Eigen::Vector3d& world, double time, std::uint16_t ring, const Eigen::Vector3d& shift) {
    const Eigen::Vector3d body = world - Eigen::Vector3d(15.0 * (time - 0.1), 0.0, 0.0);
    const Eigen::Vector3d lidar = imu_to_lidar * body - shift;
    LidarPoint p;
    p.x = static_cast<float>(lidar.x());
    p.y = static_cast<float>(lidar.y());
    p.z = static_cast<float>(lidar.z());
    p.time = static_cast<float>(time);
    p.ring = ring;
    w.scan.points.push_back(p);
    return static_cast<std::uint32_t>(w.scan.points.size() - 1);
  };
  for (int row = 0; row < 11; ++row) {
    for (int col = 0; col <= 64; ++col) {
      const double y = -8.0 + 0.25 * col;
      const double time = 0.1 * col / 64.0;  // the sweep crosses the wall from right to left
      const auto ring = static_cast<std::uint16_t>(row);
      w.features.planes.push_back(add_point({30.0, y, 0.5 + 0.25 * row}, time, ring, Eigen::Vector3d::Zero()));
      w.features.plane_curvatures.push_back(0.01F);
    }
  }
  // Edges: the last return before a surface ends falls short of it along the ray; the extractor's
  // shift puts it back, so deskewed they are on the wall too.
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d world(30.0, -7.0 + 2.0 * k, 1.2);
    const double time = 0.1 * (world.y() + 8.0) / 16.0;
    const Eigen::Vector3d in_lidar = imu_to_lidar * (world - Eigen::Vector3d(15.0 * (time - 0.1), 0.0, 0.0));
    const Eigen::Vector3d shift = 0.25 * in_lidar.normalized();
    w.features.edges.push_back(add_point(world, time, 3, shift));
    w.features.edge_shifts.push_back(shift.cast<float>());
  }
  w.scan.end_time = 0.1;
  return w;
}

TEST(DeskewFeatures, AWallSeenWhileDrivingAtItComesOutOnOnePlane) {
  const WallScan w = wall_scan();
  NavState end;
  end.time = 100.1;
  end.velocity = Eigen::Vector3d(15.0, 0.0, 0.0);
  const BeamCalibration no_calibration;
  const PoseTable relative =
      deskew_trajectory(DeskewMode::kConstantVelocity, 100.0, 100.1, NavState{}, end, {}, Eigen::Vector3d::Zero());
  const DeskewedFeatures out =
      deskew_features(w.scan, w.features, relative, 100.0, w.lidar_to_imu, no_calibration, DeskewParams{}, false);
  ASSERT_GT(out.planes.size(), 50U);
  ASSERT_GT(out.map_planes.size(), out.planes.size());
  ASSERT_EQ(out.edges.size(), 8U);
  ASSERT_EQ(out.map_plane_sources.size(), out.map_planes.size());
  for (const auto& p : out.planes) EXPECT_NEAR(p.x(), 30.0, 1e-4);
  for (const auto& p : out.map_planes) EXPECT_NEAR(p.x(), 30.0, 1e-4);
  for (const auto& p : out.edges) EXPECT_NEAR(p.x(), 30.0, 1e-4) << "the edge shift is applied before the deskew";

  // Each map point's source is its beam and the LiDAR-frame point it came from.
  for (std::size_t i = 0; i < out.map_planes.size(); ++i) {
    const Eigen::Vector3d in_body = w.lidar_to_imu * out.map_plane_sources[i].lidar;
    const double z = in_body.z();
    EXPECT_EQ(out.map_plane_sources[i].ring, static_cast<std::uint16_t>(std::lround((z - 0.5) / 0.25)));
  }

  // Without deskew the wall is smeared over the 1.5 m driven during the sweep.
  const PoseTable none = deskew_trajectory(DeskewMode::kNone, 100.0, 100.1, NavState{}, end, {}, {});
  const DeskewedFeatures smeared =
      deskew_features(w.scan, w.features, none, 100.0, w.lidar_to_imu, no_calibration, DeskewParams{}, false);
  const auto [lo, hi] = std::minmax_element(smeared.map_planes.begin(), smeared.map_planes.end(),
                                            [](const auto& a, const auto& b) { return a.x() < b.x(); });
  EXPECT_GT(hi->x() - lo->x(), 1.4);
}

// A beam whose true elevation is `offset` above its published one (the calibration knows it): its
// ground points, measured as ranges along the published direction, lie off the ground by
// range * offset; deskew_features corrects them onto it.
TEST(DeskewFeatures, AppliesTheBeamCalibrationsCorrection) {
  // Teach beam 0 a large offset (clamped at max_offset_deg) against beam 1's zero.
  BeamCalibration calibration(2);
  for (int scan = 0; scan < 300; ++scan) {
    for (int a = 0; a < 100; ++a) {
      const double j = 20.0;
      calibration.add_elevation(0, -5.0 * kDegToRad, j, j * (calibration.offset_rad(0) - 1.0 * kDegToRad), 0.03 * 0.03);
      calibration.add_elevation(1, -10.0 * kDegToRad, j, 0.0, 0.03 * 0.03);
    }
    calibration.finish_scan();
  }
  const double offset = calibration.offset_rad(0);
  ASSERT_GT(std::abs(offset), 0.01 * kDegToRad);

  const double height = 1.8;
  const double truth = -5.0 * kDegToRad;
  const double range = height / std::sin(-truth);
  Scan scan;
  ScanFeatures features;
  for (int a = 0; a < 90; ++a) {
    const double azimuth = (a * 4.0 - 180.0) * kDegToRad;
    const double published = truth - offset;
    LidarPoint p;
    p.x = static_cast<float>(range * std::cos(published) * std::cos(azimuth));
    p.y = static_cast<float>(range * std::cos(published) * std::sin(azimuth));
    p.z = static_cast<float>(range * std::sin(published));
    p.ring = 0;
    scan.points.push_back(p);
    features.planes.push_back(static_cast<std::uint32_t>(a));
    features.plane_curvatures.push_back(0.0F);
  }
  const PoseTable none = deskew_trajectory(DeskewMode::kNone, 0.0, 0.1, NavState{}, NavState{}, {}, {});
  const DeskewParams params;
  const DeskewedFeatures corrected = deskew_features(scan, features, none, 0.0, Pose{}, calibration, params, false);
  const DeskewedFeatures raw = deskew_features(scan, features, none, 0.0, Pose{}, BeamCalibration{}, params, false);
  ASSERT_EQ(corrected.map_planes.size(), 90U);
  ASSERT_EQ(raw.map_planes.size(), 90U);
  for (std::size_t i = 0; i < 90; ++i) {
    EXPECT_NEAR(corrected.map_planes[i].z(), -height, 2e-5);
    EXPECT_NEAR(corrected.map_plane_sources[i].lidar.z(), -height, 2e-5) << "the source is the corrected point";
    EXPECT_GT(std::abs(raw.map_planes[i].z() + height), 0.8 * range * std::abs(offset));
  }
}

// Three plane candidates in one 0.6 m query voxel, listed sharpest first (as the extractor does):
// the flattest query is the middle one (curvature 0.01), else the first.
TEST(DeskewFeatures, FlattestQueriesPickTheLowestCurvatureInAVoxel) {
  Scan scan;
  ScanFeatures features;
  const std::vector<Eigen::Vector3d> points = {{9.65, 0.05, 0.05}, {9.85, 0.25, 0.25}, {10.05, 0.45, 0.45}};
  const std::vector<float> curvatures = {0.3F, 0.01F, 0.2F};
  for (std::size_t i = 0; i < points.size(); ++i) {
    LidarPoint p;
    p.x = static_cast<float>(points[i].x());
    p.y = static_cast<float>(points[i].y());
    p.z = static_cast<float>(points[i].z());
    scan.points.push_back(p);
    features.planes.push_back(static_cast<std::uint32_t>(i));
    features.plane_curvatures.push_back(curvatures[i]);
  }
  const PoseTable none = deskew_trajectory(DeskewMode::kNone, 0.0, 0.1, NavState{}, NavState{}, {}, {});
  const BeamCalibration beams;
  const auto flattest = deskew_features(scan, features, none, 0.0, Pose{}, beams, DeskewParams{}, true);
  const auto first = deskew_features(scan, features, none, 0.0, Pose{}, beams, DeskewParams{}, false);
  ASSERT_EQ(flattest.map_planes.size(), 3U) << "0.2 m apart or more: all stay in the map";
  ASSERT_EQ(flattest.planes.size(), 1U);
  ASSERT_EQ(first.planes.size(), 1U);
  EXPECT_LT((flattest.planes[0] - points[1]).norm(), 1e-5);
  EXPECT_LT((first.planes[0] - points[0]).norm(), 1e-5);
}

}  // namespace
}  // namespace liod
