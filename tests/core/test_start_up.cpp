// The start-up of LidarInertialOdometry: what it reports while the speed is unknown
// (speed_search.hpp), when it decides, what it does when it cannot, and what it keeps while no
// scan comes. Synthetic scans of a vehicle at rest (level IMU at 200 Hz, 16 rings at 10 Hz over
// flat ground 1.8 m below the sensor).
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

#include "liod/algorithm_config.hpp"
#include "liod/lidar_inertial_odometry.hpp"

namespace {

constexpr double kScanPeriod = 0.1;
constexpr double kSensorHeight = 1.8;

struct Post {
  double x;
  double y;
};

// One sweep starting at `start`, every ring from -15 to 0 deg, 720 azimuths: the ground within
// 60 m, and the posts (1 m tall) where a ring meets one.
liod::Scan sweep(double start, const std::vector<Post>& posts, std::uint64_t sequence) {
  liod::Scan scan;
  scan.start_time = start;
  scan.end_time = start + kScanPeriod;
  scan.sequence = sequence;
  scan.beam_count = 16;
  constexpr int kAzimuths = 720;
  for (int a = 0; a < kAzimuths; ++a) {
    const double azimuth = 2.0 * M_PI * a / kAzimuths;
    const float time = static_cast<float>(kScanPeriod * a / kAzimuths);
    for (int ring = 0; ring < 16; ++ring) {
      const double slope = std::tan((-15.0 + ring) * M_PI / 180.0);
      const double ground = slope < 0.0 ? kSensorHeight / -slope : 1e9;
      double range = ground < 60.0 ? ground : -1.0;
      for (const auto& post : posts) {
        const double distance = std::hypot(post.x, post.y);
        const double bearing = std::atan2(post.y, post.x);
        const double height = kSensorHeight + distance * slope;
        const double off = std::remainder(azimuth - bearing, 2.0 * M_PI) * distance;
        if (std::abs(off) < 0.05 && height >= 0.0 && height <= 1.0 && (range < 0.0 || distance < range)) range = distance;
      }
      if (range < 0.0) continue;
      liod::LidarPoint p;
      const double horizontal = range;
      p.x = static_cast<float>(horizontal * std::cos(azimuth));
      p.y = static_cast<float>(horizontal * std::sin(azimuth));
      p.z = static_cast<float>(horizontal * slope);
      p.time = time;
      p.ring = static_cast<std::uint16_t>(ring);
      scan.points.push_back(p);
    }
  }
  return scan;
}

class StartUp : public ::testing::Test {
 protected:
  liod::LidarInertialOdometry odometry{liod::FrontEndConfig{}};
  liod::LidarInertialOdometry* fed_too = nullptr;  // a second odometry given the same IMU samples
  double imu_time = 0.0;

  void imu_until(double t) {
    for (; imu_time <= t + 1e-9; imu_time += 0.005) {
      liod::ImuSample s;
      s.time = imu_time;
      s.accel = Eigen::Vector3d(0.0, 0.0, 9.80665);
      odometry.add_imu(s);
      if (fed_too != nullptr) fed_too->add_imu(s);
    }
  }
  std::optional<liod::OdometryResult> scan_at(double start, const std::vector<Post>& posts = {}) {
    imu_until(start + kScanPeriod + 0.01);
    return odometry.process(sweep(start, posts, static_cast<std::uint64_t>(start * 10.0 + 0.5)));
  }
};

TEST_F(StartUp, WithoutStructureNoPoseUntilTheSearchGivesUpThenTheWidePrior) {
  const auto first = scan_at(1.0);
  ASSERT_TRUE(first.has_value());
  EXPECT_NE(first->status & liod::kStatusSpeedUnknown, 0U);
  EXPECT_NE(first->status & liod::kStatusInitializing, 0U);
  // Flat ground has no vertical structure: no pair can tell the speed, and no pose is reported.
  int silent = 0;
  double t = 1.1;
  std::optional<liod::OdometryResult> decided;
  for (; t < 4.0 && !decided; t += kScanPeriod) {
    decided = scan_at(t);
    if (!decided) ++silent;
  }
  ASSERT_TRUE(decided.has_value());
  EXPECT_GE(silent, 18);  // 2 s of scans after the first
  EXPECT_LE(silent, 20);
  EXPECT_NE(decided->status & liod::kStatusInitializing, 0U);
  EXPECT_EQ(decided->status & liod::kStatusSpeedUnknown, 0U);
  // The wide prior (odometry.init_velocity_std) stays: the LiDAR is left to find the speed.
  EXPECT_GT(decided->covariance(6, 6), 10.0);
  // And scans go on being processed.
  EXPECT_TRUE(scan_at(t).has_value());
}

TEST_F(StartUp, PostsAtRestDecideAStandstillOnTheThirdScan) {
  const std::vector<Post> posts{{8.0, 4.0}, {-6.0, 5.0}, {12.0, -4.5}, {-10.0, -6.0}, {20.0, 3.0}, {3.0, -9.0}};
  ASSERT_TRUE(scan_at(1.0, posts).has_value());
  // One pair is not enough (it can alias, speed_search): the second scan waits for the third.
  EXPECT_FALSE(scan_at(1.1, posts).has_value());
  const auto third = scan_at(1.2, posts);
  ASSERT_TRUE(third.has_value());
  EXPECT_NE(third->status & liod::kStatusInitializing, 0U);
  EXPECT_LT(third->state.velocity.norm(), 0.3);
  EXPECT_NEAR(third->covariance(6, 6), 0.25, 0.2);  // the search's 0.5 m/s, narrowed by the scan
}

TEST_F(StartUp, ALidarClockStepBackDuringTheSearchStartsItAfresh) {
  ASSERT_TRUE(scan_at(5.0).has_value());
  EXPECT_FALSE(scan_at(5.1).has_value());
  EXPECT_FALSE(scan_at(5.2).has_value());
  // Back to 2 s: not a scan to ignore until 5.2 s comes round again, but a new first scan.
  const auto restarted = scan_at(2.0);
  ASSERT_TRUE(restarted.has_value());
  EXPECT_NE(restarted->status & liod::kStatusSpeedUnknown, 0U);
}

TEST_F(StartUp, AnImuWithoutScansIsNotKeptForever) {
  // A LiDAR that never comes: ten minutes of IMU at 200 Hz, and the buffer holds one minute.
  imu_until(600.0);
  EXPECT_LE(odometry.buffered_imu_samples(), 60U * 200U + 2U);
  EXPECT_GE(odometry.buffered_imu_samples(), 60U * 200U - 2U);
  // When it comes, it starts as ever (attitude from the last second's IMU).
  const auto first = scan_at(600.0);
  ASSERT_TRUE(first.has_value());
  EXPECT_NE(first->status & liod::kStatusSpeedUnknown, 0U);
}

TEST_F(StartUp, AScanAfterMoreThanTheImuKeptIsFlaggedAsAcrossAnImuGap) {
  const std::vector<Post> posts{{8.0, 4.0}, {-6.0, 5.0}, {12.0, -4.5}, {-10.0, -6.0}, {20.0, 3.0}, {3.0, -9.0}};
  ASSERT_TRUE(scan_at(1.0, posts).has_value());
  EXPECT_FALSE(scan_at(1.1, posts).has_value());
  ASSERT_TRUE(scan_at(1.2, posts).has_value());
  // The LiDAR silent for 100 s: the IMU from 1.3 s to 41 s is gone when the next scan comes.
  const auto after = scan_at(101.3, posts);
  ASSERT_TRUE(after.has_value());
  EXPECT_NE(after->status & liod::kStatusImuGap, 0U);
  EXPECT_TRUE(after->state.position.allFinite());
}

// The daemon extracts each scan's features on the LiDAR thread and hands them over: the states
// are those of the odometry extracting them itself, the held scans of the start included, and
// what is handed over is what is registered.
TEST_F(StartUp, FeaturesExtractedElsewhereGiveTheSameStates) {
  const std::vector<Post> posts{{8.0, 4.0}, {-6.0, 5.0}, {12.0, -4.5}, {-10.0, -6.0}, {20.0, 3.0}, {3.0, -9.0}};
  const liod::FrontEndConfig config;
  liod::LidarInertialOdometry handed_over(config);
  fed_too = &handed_over;
  liod::FeatureExtractor extractor(liod::LidarInertialOdometry::feature_params(config));
  liod::ScanFeatures features;
  int compared = 0;
  for (int i = 0; i < 12; ++i) {
    const double start = 1.0 + 0.1 * i;
    imu_until(start + kScanPeriod + 0.01);
    const liod::Scan scan = sweep(start, posts, static_cast<std::uint64_t>(i));
    const auto own = odometry.process(scan);
    extractor.extract(scan, features);
    const auto given = handed_over.process(scan, features);
    ASSERT_EQ(own.has_value(), given.has_value()) << "scan " << i;
    if (!own) continue;
    EXPECT_EQ(own->status, given->status) << "scan " << i;
    EXPECT_EQ(own->plane_features, given->plane_features) << "scan " << i;
    EXPECT_EQ(own->edge_features, given->edge_features) << "scan " << i;
    EXPECT_EQ(own->state.position, given->state.position) << "scan " << i;
    EXPECT_EQ(own->state.velocity, given->state.velocity) << "scan " << i;
    EXPECT_EQ(own->state.rotation, given->state.rotation) << "scan " << i;
    EXPECT_EQ(given->features_ms, 0.0);
    ++compared;
  }
  EXPECT_GE(compared, 9);
  // Handed no features, the scan has nothing to register.
  imu_until(2.2 + kScanPeriod + 0.01);
  const auto blind = handed_over.process(sweep(2.2, posts, 12), liod::ScanFeatures{});
  ASSERT_TRUE(blind.has_value());
  EXPECT_EQ(blind->plane_features + blind->edge_features, 0U);
  EXPECT_NE(blind->status & liod::kStatusFewFeatures, 0U);
}

}  // namespace
