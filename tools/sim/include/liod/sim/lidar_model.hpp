#pragma once
// The RS-Helios-5515 as a measuring device: 32 lasers fired one after another in each 55.56 us
// block while the head spins at 600 rpm, each beam leaving from the lens centre (RX = 0.03498 m
// off the spin axis); what comes back depends on range, reflectivity and incidence, and carries
// range noise and 2.5 mm quantisation. Geometry follows the packet spec (sensors/rs-helios.md)
// only: the truth is what the spec says a decoder must invert.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "liod/sim/rng.hpp"
#include "liod/sim/traffic.hpp"
#include "liod/sim/trajectory.hpp"
#include "liod/sim/world.hpp"

namespace liod::sim {

constexpr int kChannels = 32;
constexpr int kBlocksPerRev = 1800;
constexpr double kRevPerSecond = 10.0;
constexpr double kBlockPeriod = 1.0 / (kRevPerSecond * kBlocksPerRev);  // 55.556 us
constexpr double kRangeUnit = 0.0025;                                  // m per raw count
constexpr double kLensRadius = 0.03498;                                // RX, m

/// Measured per-slot firing offsets of the Helios-32 (nebula's single-return table, us): the real
/// sensor's timing, which the uniform 1.73 us table of rs_driver only approximates.
extern const std::array<double, kChannels> kFiringOffsetUs;

struct HeliosCalibration {
  std::array<double, kChannels> vertical_deg{};
  std::array<double, kChannels> horizontal_deg{};
};

/// Reads `vert_deg,horiz_deg` lines (packet channel order). Throws std::runtime_error naming the
/// file when it is missing or malformed.
HeliosCalibration load_angles_csv(const std::string& path);

struct LidarNoise {
  bool enabled = true;
  double range_sigma = 0.018;           // m, at short range on a strong target
  double range_sigma_per_m = 1.0e-4;    // grows with range
  double weak_return_sigma = 0.006;     // m / sqrt(SNR): weak echoes jitter more
  double channel_bias_sigma = 0.004;    // m, fixed per laser (residual calibration error)
  double angle_error_deg = 0.005;       // true angles differ from the published 0.01 deg table
  double random_dropout = 0.002;
  // Added conditions (liod-sim --dropout, --rain), off by default: the fraction of returns lost
  // at random (a dirty window, interference, packet loss) and spurious near returns from rain
  // drops per second.
  double extra_dropout = 0.0;
  double rain_rate = 0.0;
};

struct LidarParams {
  double max_range = 150.0;
  double min_range = 0.2;
  double range_at_10pct = 110.0;  // 50 % detection on a 10 % target at normal incidence
  bool dual_return = false;
};

/// The vehicle's own body in the IMU frame (the LiDAR on a roof rack sees roof, bonnet and boot).
struct EgoBody {
  std::vector<Eigen::Vector3d> box_min;
  std::vector<Eigen::Vector3d> box_max;
  float reflectivity = 0.55F;
  static EgoBody passenger_car();
};

/// The range along a LiDAR-frame ray (origin `o`, unit `d`) at which it meets the vehicle's own
/// body, infinity if never.
double ego_hit_range(const EgoBody& ego, const Pose& imu_from_lidar, const Eigen::Vector3d& o, const Eigen::Vector3d& d);

/// What a surface sends back of a beam (link budget): its effective reflectivity and incidence, and
/// the SNR against a 10 % target at normal incidence that is detected half the time at
/// `range_at_10pct`.
struct Echo {
  double reflectivity = 0.0;
  double cos_incidence = 1.0;
  double snr = 0.0;
};
Echo echo_strength(const RayHit& hit, double range_at_10pct);
/// The chance that an echo of this SNR is detected, `random_dropout` lost whatever its strength.
double detection_probability(double snr, double random_dropout);

struct ChannelReturn {
  std::uint16_t raw = 0;  // distance in 2.5 mm units, 0 = no return
  std::uint8_t intensity = 0;
};

struct FiringResult {
  std::uint16_t azimuth = 0;  // 0.01 deg
  std::array<ChannelReturn, kChannels> first{};   // strongest
  std::array<ChannelReturn, kChannels> second{};  // last (dual return only)
};

class LidarModel {
 public:
  LidarModel(const HeliosCalibration& published, const LidarParams& params,
             const LidarNoise& noise, const Pose& imu_from_lidar, const EgoBody* ego,
             std::uint64_t seed);

  /// One firing (block) at azimuth step `az_step` (0..1799) starting at IMU-clock time `t`:
  /// poses of the LiDAR in the world at the block's start and at the next block's start,
  /// interpolated to each laser's firing time. `traffic` (may be null): the vehicles around.
  void fire(int az_step, double t, const Pose& start, const Pose& next, const World& world,
            TrafficScratch* traffic, RayContext& ctx, FiringResult& out) const;

  const HeliosCalibration& published() const { return published_; }
  const HeliosCalibration& true_angles() const { return true_; }
  const std::array<double, kChannels>& channel_bias() const { return bias_; }

  /// What `channel` reports of a ray that met `hit` (range noise, the channel's range bias,
  /// quantisation, intensity); false when the return is not detected. `strength`: its SNR.
  bool measure(const RayHit& hit, bool ego, int channel, Rng& rng, ChannelReturn& out, double* strength) const;

 private:
  HeliosCalibration published_;
  HeliosCalibration true_;
  LidarParams params_;
  LidarNoise noise_;
  std::array<double, kChannels> bias_{};
  // Per (azimuth step, channel): beam origin and direction in the LiDAR frame, and the range at
  // which the beam meets the ego body (inf if never).
  std::vector<Eigen::Vector3d> origin_;
  std::vector<Eigen::Vector3d> dir_;
  std::vector<float> ego_range_;
  float ego_reflectivity_ = 0.5F;

  void add_conditions(double ego_range, RayContext& ctx, ChannelReturn& first, ChannelReturn& second) const;
};

}  // namespace liod::sim
