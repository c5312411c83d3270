#pragma once
// The Velodyne HDL-64E S2 as KITTI recorded it: 64 lasers in two blocks, the upper block's 32 from
// +2 to -8.33 deg a third of a degree apart, the lower block's 32 from -8.83 to -24.33 half a
// degree apart (HDL-64E S2 user's manual; +2 to -24.8 deg of vertical field with the beams' width),
// a head turning counter-clockwise seen from above at 10 Hz, about 1.33 M shots a second (20 833
// firings of all 64 lasers a second, 2083 a turn), ranges to 120 m with an accuracy under 2 cm.
// KITTI's velodyne .bin files hold the calibrated returns of one turn as x, y, z in the sensor's
// frame and a reflectance in [0, 1]: no ring, no per-point time, no motion correction. Each
// sweep begins and ends with the head facing backward (the raw data's readme).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "liod/sim/lidar_model.hpp"
#include "liod/sim/traffic.hpp"
#include "liod/sim/trajectory.hpp"
#include "liod/sim/world.hpp"

namespace liod::sim {

constexpr int kHdlLasers = 64;
constexpr int kHdlFiringsPerTurn = 2083;
constexpr double kHdlTurnPeriod = 0.1;  // s
// The two blocks fire one laser each at once, pair k of 32 at k * 1.5 us into the 48 us firing.
constexpr double kHdlPairSpacingS = 1.5e-6;

/// The manual's nominal elevations, laser 0..31 the upper block, 32..63 the lower.
std::array<double, kHdlLasers> hdl64e_nominal_elevations_deg();

struct HdlPoint {
  float x = 0.0F;
  float y = 0.0F;
  float z = 0.0F;
  float reflectance = 0.0F;
};

struct HdlParams {
  double max_range = 120.0;
  double min_range = 0.9;        // the returns KITTI's files hold start about here
  double range_at_10pct = 50.0;  // 50 m on pavement (10 %), 120 m on cars (80 %): the data sheet
  // How far a unit's lasers point from the manual's table (each laser's own calibration file tells
  // the truth): uniform per laser. Within a sixth of a degree, so that the nominal table still
  // names each return's laser (half the upper block's spacing).
  double unit_elevation_spread_deg = 0.05;
};

class Hdl64eModel {
 public:
  /// `noise`: range noise, per-laser range bias, residual angle error of the calibration file
  /// (angle_error_deg: the written points' direction against the beam's true one), dropouts.
  Hdl64eModel(const HdlParams& params, const LidarNoise& noise, const Pose& imu_from_lidar, const EgoBody* ego,
              std::uint64_t seed);

  /// One turn of the head from IMU-clock time `t0` (facing backward) to t0 + 0.1 s: the returns as
  /// KITTI's .bin holds them, in the LiDAR frame at each firing. `lidar_pose(t)`: the LiDAR's world
  /// pose at IMU-clock time t.
  template <class PoseAt>
  void sweep(double t0, const PoseAt& lidar_pose, const World& world, RayContext& ctx,
             std::vector<HdlPoint>& out, std::uint64_t* rays) const {
    out.clear();
    Pose cur = lidar_pose(t0);
    for (int j = 0; j < kHdlFiringsPerTurn; ++j) {
      const double t = t0 + kHdlTurnPeriod * j / kHdlFiringsPerTurn;
      const Pose next = lidar_pose(t0 + kHdlTurnPeriod * (j + 1) / kHdlFiringsPerTurn);
      fire(j, t, cur, next, world, ctx, out);
      cur = next;
    }
    if (rays != nullptr) *rays += static_cast<std::uint64_t>(kHdlFiringsPerTurn) * kHdlLasers;
  }

  const std::array<double, kHdlLasers>& true_elevations_deg() const { return true_el_; }
  const std::array<double, kHdlLasers>& range_bias() const { return bias_; }

 private:
  void fire(int step, double t, const Pose& start, const Pose& next, const World& world, RayContext& ctx,
            std::vector<HdlPoint>& out) const;
  bool measure(const RayHit& hit, bool ego, int laser, Rng& rng, double& range, float& reflectance) const;

  HdlParams params_;
  LidarNoise noise_;
  std::array<double, kHdlLasers> true_el_{};
  std::array<double, kHdlLasers> bias_{};
  // Per (firing step, laser): the beam's true direction, the direction the calibration file
  // writes its return along, and the range at which it meets the ego body (inf if never).
  std::vector<Eigen::Vector3d> dir_;
  std::vector<Eigen::Vector3f> written_dir_;
  std::vector<float> ego_range_;
  float ego_reflectivity_ = 0.5F;
};

}  // namespace liod::sim
