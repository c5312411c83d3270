#include "liod/sim/lidar_model.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "liod/sim/angles.hpp"

namespace liod::sim {

namespace {
constexpr std::uint64_t kCalibStream = 0x63616C6962ULL;

std::size_t slot(int az_step, int ch) {
  return static_cast<std::size_t>(az_step) * kChannels + static_cast<std::size_t>(ch);
}
}  // namespace

const std::array<double, kChannels> kFiringOffsetUs = {
    0.00,  1.57,  3.15,  4.72,  6.30,  7.87,  9.45,  11.36, 13.26, 15.17, 17.08,
    18.99, 20.56, 22.14, 23.71, 25.29, 26.53, 29.01, 27.77, 30.25, 31.49, 32.73,
    33.98, 35.22, 36.46, 37.70, 38.94, 40.18, 41.42, 42.67, 43.91, 45.15};

HeliosCalibration load_angles_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error("cannot open LiDAR angle table '" + path +
                             "' (pass --angles FILE with 32 lines 'vert_deg,horiz_deg')");
  }
  HeliosCalibration cal;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) {
      continue;
    }
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ls(line);
    double v = 0.0;
    double h = 0.0;
    if (!(ls >> v >> h) || n >= kChannels) {
      throw std::runtime_error("angle table '" + path + "': bad or extra line " +
                               std::to_string(n + 1) + ": '" + line + "'");
    }
    cal.vertical_deg[static_cast<std::size_t>(n)] = v;
    cal.horizontal_deg[static_cast<std::size_t>(n)] = h;
    ++n;
  }
  if (n != kChannels) {
    throw std::runtime_error("angle table '" + path + "' has " + std::to_string(n) +
                             " lines, expected 32");
  }
  return cal;
}

double ego_hit_range(const EgoBody& ego, const Pose& imu_from_lidar, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::Vector3d ob = imu_from_lidar.rotation * o + imu_from_lidar.translation;
  const Eigen::Vector3d db = imu_from_lidar.rotation * d;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < ego.box_min.size(); ++b) {
    double tn = -1e18;
    double tf = 1e18;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(db[a]) < 1e-12) {
        if (ob[a] < ego.box_min[b][a] || ob[a] > ego.box_max[b][a]) {
          tn = 1e18;
        }
        continue;
      }
      double t1 = (ego.box_min[b][a] - ob[a]) / db[a];
      double t2 = (ego.box_max[b][a] - ob[a]) / db[a];
      if (t1 > t2) {
        std::swap(t1, t2);
      }
      tn = std::max(tn, t1);
      tf = std::min(tf, t2);
    }
    if (tn <= tf && tn > 0.0) {
      best = std::min(best, static_cast<double>(static_cast<float>(tn)));
    }
  }
  return best;
}

Echo echo_strength(const RayHit& hit, double range_at_10pct) {
  Echo e;
  e.reflectivity = hit.reflectivity;
  e.cos_incidence = std::max(hit.cos_incidence, 1e-4);
  switch (hit.kind) {
    case SurfaceKind::Retroreflective:
      e.reflectivity = 20.0;
      e.cos_incidence = std::pow(e.cos_incidence, 0.3);
      break;
    case SurfaceKind::Glass:
      // Specular: only a beam nearly normal to the pane comes back.
      e.reflectivity = e.cos_incidence > 0.985 ? 0.8 : 0.02;
      break;
    case SurfaceKind::Diffuse:
    case SurfaceKind::Porous:
      break;
  }
  e.snr = e.reflectivity * e.cos_incidence / 0.1 * std::pow(range_at_10pct / std::max(hit.range, 0.5), 2.0);
  return e;
}

double detection_probability(double snr, double random_dropout) {
  // A logistic in log(SNR): 50 % at SNR 1.
  return (1.0 - random_dropout) / (1.0 + std::pow(snr, -2.8));
}

EgoBody EgoBody::passenger_car() {
  // IMU frame: x forward, z up, the IMU 0.80 m above the road at mid-wheelbase.
  EgoBody e;
  e.box_min = {Eigen::Vector3d(-2.35, -0.92, -0.45), Eigen::Vector3d(-1.45, -0.85, 0.20)};
  e.box_max = {Eigen::Vector3d(2.35, 0.92, 0.20), Eigen::Vector3d(0.85, 0.85, 0.65)};
  return e;
}

LidarModel::LidarModel(const HeliosCalibration& published, const LidarParams& params,
                       const LidarNoise& noise, const Pose& imu_from_lidar, const EgoBody* ego,
                       std::uint64_t seed)
    : published_(published), true_(published), params_(params), noise_(noise) {
  Rng rng(derive_seed(seed, kCalibStream));
  for (int c = 0; c < kChannels; ++c) {
    const auto i = static_cast<std::size_t>(c);
    // Angles are published rounded to 0.01 deg and the range offset is calibrated to a few mm:
    // the unit is always slightly different from its own table.
    true_.vertical_deg[i] += rng.uniform(-noise.angle_error_deg, noise.angle_error_deg);
    true_.horizontal_deg[i] += rng.uniform(-noise.angle_error_deg, noise.angle_error_deg);
    bias_[i] = rng.gaussian(noise.channel_bias_sigma);
  }
  if (!noise.enabled) {
    true_ = published_;
    bias_.fill(0.0);
  }
  origin_.resize(slot(kBlocksPerRev, 0));
  dir_.resize(origin_.size());
  ego_range_.assign(origin_.size(), std::numeric_limits<float>::infinity());
  for (int k = 0; k < kBlocksPerRev; ++k) {
    for (int c = 0; c < kChannels; ++c) {
      const auto i = static_cast<std::size_t>(c);
      const double az_ch = (k * 20.0 + 20.0 * kFiringOffsetUs[i] * 1e-6 / kBlockPeriod) / 100.0;
      const double az_f = az_ch + true_.horizontal_deg[i];
      const double el = true_.vertical_deg[i] * kDeg;
      const Eigen::Vector3d o(kLensRadius * std::cos(az_ch * kDeg), -kLensRadius * std::sin(az_ch * kDeg), 0.0);
      const Eigen::Vector3d d(std::cos(el) * std::cos(az_f * kDeg), -std::cos(el) * std::sin(az_f * kDeg),
                              std::sin(el));
      origin_[slot(k, c)] = o;
      dir_[slot(k, c)] = d;
      if (ego == nullptr) {
        continue;
      }
      ego_range_[slot(k, c)] = static_cast<float>(ego_hit_range(*ego, imu_from_lidar, o, d));
      ego_reflectivity_ = ego->reflectivity;
    }
  }
}

bool LidarModel::measure(const RayHit& hit, bool ego, int channel, Rng& rng, ChannelReturn& out,
                         double* strength) const {
  const double d = hit.range;
  const Echo echo = echo_strength(hit, params_.range_at_10pct);
  const double rho = echo.reflectivity;
  const double cosi = echo.cos_incidence;
  const double snr = echo.snr;
  *strength = snr;
  const double p_detect = detection_probability(snr, noise_.random_dropout);
  if (!ego && rng.uniform() >= p_detect) {
    return false;
  }
  double measured = d;
  if (noise_.enabled) {
    const double sigma = noise_.range_sigma + noise_.range_sigma_per_m * d +
                         noise_.weak_return_sigma / std::sqrt(std::max(snr, 0.3));
    measured += rng.gaussian(sigma) + bias_[static_cast<std::size_t>(channel)];
  }
  if (measured < params_.min_range || measured > params_.max_range) {
    return false;
  }
  const long raw = std::lround(measured / kRangeUnit);
  out.raw = static_cast<std::uint16_t>(std::clamp(raw, 1L, 65535L));
  double intensity = 0.0;
  if (hit.kind == SurfaceKind::Retroreflective) {
    intensity = 200.0 + 55.0 * cosi;
  } else {
    intensity = 100.0 * std::min(rho, 1.0) * (0.3 + 0.7 * cosi);
  }
  intensity *= 1.0 + 0.08 * rng.gaussian();
  out.intensity = static_cast<std::uint8_t>(std::clamp(std::lround(intensity), 1L, 255L));
  return true;
}

void LidarModel::add_conditions(double ego_range, RayContext& ctx, ChannelReturn& first,
                                ChannelReturn& second) const {
  if (noise_.rain_rate > 0.0) {
    // A drop in the beam near the lens returns a weak echo that, so close, is still the strongest
    // (the 1/d^2 of the link budget); the drop's distance is that of the nearest drop met, i.e.
    // exponential, and the detection falls off with range, hence the short mean.
    const double p = noise_.rain_rate / (kChannels * kBlocksPerRev * kRevPerSecond);
    const double u = ctx.aux().uniform();
    const double range = 0.4 + ctx.aux().exponential(1.2);
    const int intensity = ctx.aux().uniform_int(1, 6);
    const bool in_front = first.raw == 0 || range < first.raw * kRangeUnit;
    if (u < p && in_front && range < std::min(ego_range, 8.0)) {
      first.raw = static_cast<std::uint16_t>(std::lround(range / kRangeUnit));
      first.intensity = static_cast<std::uint8_t>(intensity);
      if (!params_.dual_return) {
        second = first;
      }
    }
  }
  if (noise_.extra_dropout > 0.0) {
    if (first.raw != 0 && ctx.aux().uniform() < noise_.extra_dropout) {
      first = ChannelReturn{};
    }
    if (!params_.dual_return) {
      second = first;
    } else if (second.raw != 0 && ctx.aux().uniform() < noise_.extra_dropout) {
      second = ChannelReturn{};
    }
  }
}

void LidarModel::fire(int az_step, double t, const Pose& start, const Pose& next, const World& world,
                      TrafficScratch* traffic, RayContext& ctx, FiringResult& out) const {
  out.azimuth = static_cast<std::uint16_t>(az_step * 20);
  const bool moving = traffic != nullptr && traffic->traffic != nullptr;
  if (moving) {
    const Eigen::Vector3d mid = start.rotation * dir_[slot(az_step, 0)];
    traffic->traffic->boxes_toward(traffic->near, t, start.translation.head<2>(), mid.head<2>().normalized(),
                                   traffic->boxes);
  }
  const bool conditions = noise_.rain_rate > 0.0 || noise_.extra_dropout > 0.0;
  for (int c = 0; c < kChannels; ++c) {
    const auto i = static_cast<std::size_t>(c);
    const double alpha = kFiringOffsetUs[i] * 1e-6 / kBlockPeriod;
    const double dt = kFiringOffsetUs[i] * 1e-6;
    ctx.set_time(t + dt);
    auto cast = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& dir, double range, RayHit& hit) {
      bool found = world.cast(from, dir, range, ctx, hit);
      if (moving && !traffic->boxes.empty()) {
        found = intersect_moving(traffic->boxes, dt, from, dir, found ? hit.range : range, ctx.rng(), hit) || found;
      }
      return found;
    };
    // Over 55 us, linear interpolation of the pose is exact to nanometres.
    const Eigen::Matrix3d R = (1.0 - alpha) * start.rotation + alpha * next.rotation;
    const Eigen::Vector3d p = (1.0 - alpha) * start.translation + alpha * next.translation;
    const Eigen::Vector3d o = R * origin_[slot(az_step, c)] + p;
    const Eigen::Vector3d d = (R * dir_[slot(az_step, c)]).normalized();
    const double ego_t = ego_range_[slot(az_step, c)];
    RayHit hit;
    const bool found = cast(o, d, std::min(params_.max_range + 1.0, ego_t), hit);
    ChannelReturn first{};
    ChannelReturn second{};
    double s1 = 0.0;
    if (!found && std::isfinite(ego_t)) {
      RayHit eh;
      eh.range = ego_t;
      eh.cos_incidence = 0.5;
      eh.reflectivity = ego_reflectivity_;
      measure(eh, true, c, ctx.rng(), first, &s1);
      second = first;
    } else if (found) {
      const bool got = measure(hit, false, c, ctx.rng(), first, &s1);
      second = first;
      if (params_.dual_return && hit.kind == SurfaceKind::Porous) {
        // A beam partly blocked by foliage also returns from what lies behind it.
        RayHit behind;
        const double t0 = hit.range + 0.5;
        if (cast(o + d * t0, d, params_.max_range + 1.0 - t0, behind)) {
          behind.range += t0;
          ChannelReturn last{};
          double s2 = 0.0;
          if (measure(behind, false, c, ctx.rng(), last, &s2)) {
            if (!got || s2 > s1) {
              first = last;
            }
            second = last;
          }
        }
      }
    }
    if (conditions) {
      add_conditions(ego_t, ctx, first, second);
    }
    out.first[i] = first;
    out.second[i] = second;
  }
}

}  // namespace liod::sim
