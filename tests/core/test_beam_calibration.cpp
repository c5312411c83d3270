#include "beam_direction.hpp"
#include "liod/angles.hpp"
#include "liod/beam_calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace liod {
namespace {

TEST(BeamCalibration, ElevationDerivativeIsHowAPointMovesWithItsElevation) {
  const double range = 23.0;
  const double elevation = -4.0 * kDegToRad;
  const double azimuth = 2.2;
  const double h = 1e-6;
  const Eigen::Vector3d numeric =
      range * (test::beam_direction(elevation + h, azimuth) - test::beam_direction(elevation - h, azimuth)) / (2.0 * h);
  const Eigen::Vector3d analytic = BeamCalibration::elevation_derivative(range * test::beam_direction(elevation, azimuth));
  EXPECT_LT((numeric - analytic).norm(), 1e-6) << analytic.transpose() << " vs " << numeric.transpose();
  EXPECT_EQ(BeamCalibration::elevation_derivative(Eigen::Vector3d(0, 0, 5)), Eigen::Vector3d::Zero());
}

// A level sensor 1.8 m above flat ground whose beams point slightly off their published elevations
// (up to the RS-Helios table's 0.005 deg rounding): each beam's points, measured as a range along
// its published direction, lie off the ground by about range * offset. Fed their residuals against
// the ground, the calibration learns each beam's offset, except the pattern proportional to the
// elevation that a pose cannot tell from a height (the gauge, held at zero).
TEST(BeamCalibration, LearnsEachBeamsOffsetFromItsGroundResidualsUpToTheHeightPattern) {
  const double height = 1.8;
  const std::vector<double> published_deg = {-12.9, -9.89, -7.91, -6.53, -5.13, -3.96, -2.67, -1.33, 5.0};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> error(-0.005, 0.005);
  std::vector<double> true_offset;
  for (std::size_t k = 0; k + 1 < published_deg.size(); ++k) true_offset.push_back(error(rng) * kDegToRad);
  true_offset.push_back(0.004 * kDegToRad);  // the upward beam never sees the ground

  BeamCalibration calibration(published_deg.size());
  for (int scan = 0; scan < 2000; ++scan) {
    for (std::size_t k = 0; k < published_deg.size(); ++k) {
      const auto beam = static_cast<std::uint16_t>(k);
      const double published = published_deg[k] * kDegToRad;
      const double truth = published + true_offset[k];
      if (truth >= 0.0) continue;
      const double range = height / std::sin(-truth);
      for (int a = 0; a < 180; ++a) {
        const Eigen::Vector3d point = calibration.correct(range * test::beam_direction(published, a * 2.0 * kDegToRad), beam);
        const double residual = point.z() + height;  // the ground plane z = -height, normal up
        const double jacobian = BeamCalibration::elevation_derivative(point).z();
        calibration.add_elevation(beam, std::atan2(point.z(), std::hypot(point.x(), point.y())), jacobian, residual,
                        0.03 * 0.03);
      }
    }
    calibration.finish_scan();
  }

  // The truth without its height pattern (least squares through zero over the ground beams).
  double ee = 0.0;
  double et = 0.0;
  for (std::size_t k = 0; k + 1 < published_deg.size(); ++k) {
    ee += published_deg[k] * published_deg[k];
    et += published_deg[k] * true_offset[k];
  }
  double spread_before = 0.0;
  double spread_after = 0.0;
  for (std::size_t k = 0; k + 1 < published_deg.size(); ++k) {
    const double expected = true_offset[k] - et / ee * published_deg[k];
    const double learned = calibration.offset_rad(static_cast<std::uint16_t>(k));
    EXPECT_NEAR(learned / kDegToRad, expected / kDegToRad, 0.0005) << "beam " << k << " true " << true_offset[k] / kDegToRad;
    spread_before += expected * expected;
    spread_after += (expected - learned) * (expected - learned);
  }
  EXPECT_LT(spread_after, 0.01 * spread_before);
  EXPECT_EQ(calibration.offset_rad(static_cast<std::uint16_t>(published_deg.size() - 1)), 0.0) << "no ground, no data";
  EXPECT_EQ(calibration.offset_rad(99), 0.0) << "no such beam";
}

TEST(BeamCalibration, AnOffsetFarBeyondARoundingErrorIsClampedAndBadResidualsIgnored) {
  BeamCalibration calibration(2);
  const double range = 20.0;
  const double elevation = -5.0 * kDegToRad;
  for (int scan = 0; scan < 500; ++scan) {
    for (int a = 0; a < 100; ++a) {
      const Eigen::Vector3d point = calibration.correct(range * test::beam_direction(elevation, a * 0.06), 0);
      const double jacobian = BeamCalibration::elevation_derivative(point).z();
      // Beam 0 reads 1 deg low (its ground 35 cm off at 20 m); beam 1 a steady 0 to keep the gauge fit defined.
      calibration.add_elevation(0, elevation, jacobian, jacobian * (calibration.offset_rad(0) - 1.0 * kDegToRad), 0.03 * 0.03);
      calibration.add_elevation(1, 2.0 * elevation, jacobian, 0.0, 0.03 * 0.03);
      calibration.add_elevation(0, elevation, std::nan(""), 1.0, 0.03 * 0.03);
      calibration.add_elevation(0, elevation, jacobian, 1.0, 0.0);
    }
    calibration.finish_scan();
  }
  EXPECT_LE(std::abs(calibration.offset_rad(0)), 0.02 * kDegToRad + 1e-12);
  EXPECT_GT(std::abs(calibration.offset_rad(0)), 0.0);
}

// A sensor in a box-shaped hall (walls 6-14 m away, floor 1.8 m below, ceiling 4 m above) whose
// channels each read their ranges a few millimetres long or short: every point lies off its
// surface by the offset times the cosine of its incidence. Fed those residuals, the calibration
// learns each beam's range offset, less the beams' mean (a common offset, which only a surface seen
// from both sides shows, is left to the sensor's own calibration), and leaves the elevations alone.
TEST(BeamCalibration, LearnsEachBeamsRangeOffsetLessTheirMeanFromPlaneResiduals) {
  const std::vector<double> elevation_deg = {-25.0, -15.0, -8.0, -3.0, 0.0, 4.0, 9.0, 14.0};
  std::mt19937 rng(11);
  std::normal_distribution<double> offset(0.0, 0.004);
  std::normal_distribution<double> range_noise(0.0, 0.02);
  std::vector<double> true_offset;
  for (std::size_t k = 0; k < elevation_deg.size(); ++k) true_offset.push_back(offset(rng));
  // Planes n . x + d = 0, normals pointing into the hall.
  const std::vector<std::pair<Eigen::Vector3d, double>> planes = {
      {Eigen::Vector3d(0, 0, 1), 1.8},  {Eigen::Vector3d(0, 0, -1), 4.0}, {Eigen::Vector3d(1, 0, 0), 6.0},
      {Eigen::Vector3d(-1, 0, 0), 14.0}, {Eigen::Vector3d(0, 1, 0), 9.0}, {Eigen::Vector3d(0, -1, 0), 7.0}};
  BeamCalibrationParams params;
  params.learn_ranges = true;
  BeamCalibration calibration(elevation_deg.size(), params);
  for (int scan = 0; scan < 600; ++scan) {
    for (std::size_t k = 0; k < elevation_deg.size(); ++k) {
      const auto beam = static_cast<std::uint16_t>(k);
      for (int a = 0; a < 90; ++a) {
        const Eigen::Vector3d ray = test::beam_direction(elevation_deg[k] * kDegToRad, (a * 4.0 + 0.3 * scan) * kDegToRad);
        // The nearest surface along the ray.
        double range = 1e9;
        const std::pair<Eigen::Vector3d, double>* hit = nullptr;
        for (const auto& plane : planes) {
          const double along = -plane.first.dot(ray);
          if (along <= 1e-6) continue;
          const double t = plane.second / along;
          if (t < range) {
            range = t;
            hit = &plane;
          }
        }
        const double measured = range + true_offset[k] + range_noise(rng);
        const Eigen::Vector3d point = calibration.correct(measured * ray, beam);
        const double residual = hit->first.dot(point) + hit->second;
        calibration.add_range(beam, hit->first.dot(point.normalized()), residual, 0.02 * 0.02);
      }
    }
    calibration.finish_scan();
  }
  double mean = 0.0;
  for (const double o : true_offset) mean += o / static_cast<double>(true_offset.size());
  double spread_before = 0.0;
  double spread_after = 0.0;
  for (std::size_t k = 0; k < elevation_deg.size(); ++k) {
    const auto beam = static_cast<std::uint16_t>(k);
    const double expected = -(true_offset[k] - mean);  // the correction takes the reading's offset off
    EXPECT_NEAR(calibration.range_offset_m(beam), expected, 0.0005) << "beam " << k << " true " << true_offset[k];
    EXPECT_EQ(calibration.offset_rad(beam), 0.0) << "no elevation data, no elevation offset";
    spread_before += expected * expected;
    spread_after += std::pow(calibration.range_offset_m(beam) - expected, 2);
  }
  EXPECT_LT(spread_after, 0.02 * spread_before);
}

TEST(BeamCalibration, RangeResidualsAreIgnoredUnlessRangesAreLearned) {
  BeamCalibration calibration(2);
  for (int scan = 0; scan < 200; ++scan) {
    for (int i = 0; i < 100; ++i) {
      calibration.add_range(0, 1.0, 0.01, 0.02 * 0.02);
      calibration.add_range(1, 1.0, -0.01, 0.02 * 0.02);
    }
    calibration.finish_scan();
  }
  EXPECT_EQ(calibration.range_offset_m(0), 0.0);
  EXPECT_EQ(calibration.range_offset_m(1), 0.0);
  EXPECT_EQ(calibration.correct(Eigen::Vector3d(10, 0, 0), 0), Eigen::Vector3d(10, 0, 0));
}

}  // namespace
}  // namespace liod
