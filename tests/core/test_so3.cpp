#include <gtest/gtest.h>

#include <cmath>

#include "liod/angles.hpp"
#include "liod/so3.hpp"

namespace {

using liod::kDegToRad;

const Eigen::Vector3d kUp = Eigen::Vector3d::UnitZ();

// A body pitched, rolled and headed arbitrarily, as an IMU mounted on a vehicle on a slope.
Eigen::Matrix3d mounted_body() { return liod::so3::exp(Eigen::Vector3d(0.08, -0.15, 2.2)); }

TEST(So3, TurnRateAboutTheVerticalIsTheYawRateWhateverTheBodysTilt) {
  const Eigen::Matrix3d from = mounted_body();
  for (const double rate_deg_s : {-15.0, -3.0, 0.5, 12.0}) {
    const Eigen::Matrix3d to = liod::so3::exp(kUp * rate_deg_s * kDegToRad * 0.1) * from;  // turned in the world
    EXPECT_NEAR(liod::so3::turn_rate_about(from, to, kUp, 0.1), rate_deg_s * kDegToRad, 1e-12);
    EXPECT_NEAR(liod::so3::turn_rate_about(from, to, -kUp, 0.1), -rate_deg_s * kDegToRad, 1e-12);
  }
}

TEST(So3, PitchingAndRollingIsNoTurn) {
  const Eigen::Matrix3d from = mounted_body();
  const Eigen::Matrix3d pitched = liod::so3::exp(Eigen::Vector3d(0.0, 0.02, 0.0)) * from;
  const Eigen::Matrix3d rolled = liod::so3::exp(Eigen::Vector3d(0.03, 0.0, 0.0)) * from;
  EXPECT_NEAR(liod::so3::turn_rate_about(from, pitched, kUp, 0.1), 0.0, 1e-12);
  EXPECT_NEAR(liod::so3::turn_rate_about(from, rolled, kUp, 0.1), 0.0, 1e-12);
  // A turn with the body rocking on its suspension keeps the turn's rate, to second order.
  const Eigen::Matrix3d both = liod::so3::exp(Eigen::Vector3d(0.004, -0.003, 0.0)) * liod::so3::exp(kUp * 0.02) * from;
  EXPECT_NEAR(liod::so3::turn_rate_about(from, both, kUp, 0.1), 0.2, 2e-3);
}

}  // namespace
