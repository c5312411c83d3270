#include "liod/sim/hdl64e.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "liod/sim/angles.hpp"

namespace liod::sim {

namespace {
constexpr std::uint64_t kHdlCalibStream = 0x68646C3634ULL;

std::size_t hdl_slot(int step, int laser) {
  return static_cast<std::size_t>(step) * kHdlLasers + static_cast<std::size_t>(laser);
}

/// The head's azimuth (deg, counter-clockwise from the x axis) when firing `step` of a turn begins.
double step_azimuth_deg(double step) { return 180.0 + 360.0 * step / kHdlFiringsPerTurn; }

Eigen::Vector3d hdl_direction(double elevation_deg, double azimuth_deg) {
  const double el = elevation_deg * kDeg;
  const double az = azimuth_deg * kDeg;
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}
}  // namespace

std::array<double, kHdlLasers> hdl64e_nominal_elevations_deg() {
  std::array<double, kHdlLasers> e{};
  for (int k = 0; k < 32; ++k) {
    e[static_cast<std::size_t>(k)] = 2.0 - k / 3.0;
    e[static_cast<std::size_t>(32 + k)] = -8.83 - 0.5 * k;
  }
  return e;
}

Hdl64eModel::Hdl64eModel(const HdlParams& params, const LidarNoise& noise, const Pose& imu_from_lidar,
                         const EgoBody* ego, std::uint64_t seed)
    : params_(params), noise_(noise) {
  Rng rng(derive_seed(seed, kHdlCalibStream));
  const auto nominal = hdl64e_nominal_elevations_deg();
  // The unit's own beams, and what its calibration file says of them.
  std::array<double, kHdlLasers> written_el{};
  std::array<double, kHdlLasers> written_az{};
  for (std::size_t i = 0; i < kHdlLasers; ++i) {
    true_el_[i] = nominal[i] + rng.uniform(-params.unit_elevation_spread_deg, params.unit_elevation_spread_deg);
    written_el[i] = true_el_[i] + rng.uniform(-noise.angle_error_deg, noise.angle_error_deg);
    written_az[i] = rng.uniform(-noise.angle_error_deg, noise.angle_error_deg);
    bias_[i] = rng.gaussian(noise.channel_bias_sigma);
  }
  if (!noise.enabled) {
    written_el = true_el_;
    written_az.fill(0.0);
    bias_.fill(0.0);
  }
  dir_.resize(hdl_slot(kHdlFiringsPerTurn, 0));
  written_dir_.resize(dir_.size());
  ego_range_.assign(dir_.size(), std::numeric_limits<float>::infinity());
  if (ego != nullptr) ego_reflectivity_ = ego->reflectivity;
  for (int j = 0; j < kHdlFiringsPerTurn; ++j) {
    for (int l = 0; l < kHdlLasers; ++l) {
      const auto i = static_cast<std::size_t>(l);
      const double pair = static_cast<double>(l % 32);
      const double az = step_azimuth_deg(j + pair * kHdlPairSpacingS * kHdlFiringsPerTurn / kHdlTurnPeriod);
      dir_[hdl_slot(j, l)] = hdl_direction(true_el_[i], az);
      written_dir_[hdl_slot(j, l)] = hdl_direction(written_el[i], az + written_az[i]).cast<float>();
      if (ego != nullptr) {
        ego_range_[hdl_slot(j, l)] = static_cast<float>(ego_hit_range(*ego, imu_from_lidar, Eigen::Vector3d::Zero(), dir_[hdl_slot(j, l)]));
      }
    }
  }
}

bool Hdl64eModel::measure(const RayHit& hit, bool ego, int laser, Rng& rng, double& range, float& reflectance) const {
  const Echo echo = echo_strength(hit, params_.range_at_10pct);
  if (!ego && rng.uniform() >= detection_probability(echo.snr, noise_.random_dropout)) return false;
  range = hit.range;
  if (noise_.enabled) {
    const double sigma = noise_.range_sigma + noise_.range_sigma_per_m * hit.range +
                         noise_.weak_return_sigma / std::sqrt(std::max(echo.snr, 0.3));
    range += rng.gaussian(sigma) + bias_[static_cast<std::size_t>(laser)];
  }
  if (range < params_.min_range || range > params_.max_range) return false;
  // KITTI's reflectance: the return's strength scaled to [0, 1].
  const double r = hit.kind == SurfaceKind::Retroreflective ? 0.9 + 0.1 * echo.cos_incidence
                                                            : std::min(echo.reflectivity, 1.0) * (0.3 + 0.7 * echo.cos_incidence);
  reflectance = static_cast<float>(std::clamp(r * (1.0 + 0.08 * rng.gaussian()), 0.0, 1.0));
  return true;
}

void Hdl64eModel::fire(int step, double t, const Pose& start, const Pose& next, const World& world, RayContext& ctx,
                       std::vector<HdlPoint>& out) const {
  const double step_period = kHdlTurnPeriod / kHdlFiringsPerTurn;
  for (int l = 0; l < kHdlLasers; ++l) {
    const double dt = static_cast<double>(l % 32) * kHdlPairSpacingS;
    const double alpha = dt / step_period;
    ctx.set_time(t + dt);
    // Over 48 us, linear interpolation of the pose is exact to nanometres.
    const Eigen::Matrix3d R = (1.0 - alpha) * start.rotation + alpha * next.rotation;
    const Eigen::Vector3d o = (1.0 - alpha) * start.translation + alpha * next.translation;
    const Eigen::Vector3d d = (R * dir_[hdl_slot(step, l)]).normalized();
    const double ego_t = ego_range_[hdl_slot(step, l)];
    RayHit hit;
    const bool found = world.cast(o, d, std::min(params_.max_range + 1.0, ego_t), ctx, hit);
    double range = 0.0;
    float reflectance = 0.0F;
    bool got = false;
    if (!found && std::isfinite(ego_t)) {
      RayHit eh;
      eh.range = ego_t;
      eh.cos_incidence = 0.5;
      eh.reflectivity = ego_reflectivity_;
      got = measure(eh, true, l, ctx.rng(), range, reflectance);
    } else if (found) {
      got = measure(hit, false, l, ctx.rng(), range, reflectance);
    }
    if (!got) continue;
    // The file's point: the range along the beam as the calibration file has it, in the frame of
    // the sensor at this firing (KITTI's scans are not corrected for the motion).
    const Eigen::Vector3f p = written_dir_[hdl_slot(step, l)] * static_cast<float>(range);
    out.push_back(HdlPoint{p.x(), p.y(), p.z(), reflectance});
  }
}

}  // namespace liod::sim
