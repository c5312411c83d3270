#include "liod/drivers/cloud_sweep.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace liod::drivers {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

/// Seconds after the sweep's start at which a head turning from start_azimuth_deg saw this azimuth.
float time_from_azimuth(double azimuth_rad, const CloudScanConfig& config) {
  const double turn = 2.0 * std::numbers::pi;
  double travelled = config.clockwise ? config.start_azimuth_deg * kDegToRad - azimuth_rad
                                      : azimuth_rad - config.start_azimuth_deg * kDegToRad;
  travelled = std::fmod(travelled, turn);
  if (travelled < 0.0) travelled += turn;
  if (travelled >= turn) travelled = 0.0;  // a tiny negative remainder rounds up to a whole turn
  return static_cast<float>(travelled / turn * config.sweep_period_s);
}

}  // namespace

BeamTable::BeamTable(const std::vector<double>& elevations_deg, double max_error_deg)
    : max_error_rad_(max_error_deg * kDegToRad) {
  sorted_rad_.reserve(elevations_deg.size());
  for (const double e : elevations_deg) sorted_rad_.push_back(e * kDegToRad);
  std::sort(sorted_rad_.begin(), sorted_rad_.end());
}

int BeamTable::ring_of(double elevation_rad) const {
  if (sorted_rad_.empty() || !std::isfinite(elevation_rad)) return -1;
  const auto above = std::lower_bound(sorted_rad_.begin(), sorted_rad_.end(), elevation_rad);
  auto best = above;
  if (above == sorted_rad_.end() || (above != sorted_rad_.begin() && elevation_rad - above[-1] < *above - elevation_rad)) {
    best = std::prev(above);
  }
  if (std::abs(*best - elevation_rad) > max_error_rad_) return -1;
  return static_cast<int>(best - sorted_rad_.begin());
}

Scan make_scan(const CloudSweep& sweep, const CloudScanConfig& config, CloudScanStats* stats) {
  CloudScanStats counts;
  counts.points_in = sweep.points.size();
  const BeamTable beams(config.beam_elevations_deg, config.max_elevation_error_deg);
  if (!sweep.has_ring && beams.beams() == 0) {
    throw std::invalid_argument("a cloud without rings needs the sensor's beam elevations");
  }
  if (beams.beams() > std::numeric_limits<std::uint16_t>::max()) throw std::invalid_argument("beam table too large");
  Scan scan;
  scan.sequence = sweep.sequence;
  scan.start_time = sweep.start_time;
  scan.points.reserve(sweep.points.size());
  const Eigen::Isometry3d cloud_to_head = config.head_in_cloud.inverse();
  std::uint16_t highest_ring = 0;
  float latest = 0.0F;
  for (const LidarPoint& p : sweep.points) {
    const Eigen::Vector3d q = cloud_to_head * Eigen::Vector3d(p.x, p.y, p.z);
    const double horizontal = std::hypot(q.x(), q.y());
    if (!(q.norm() >= config.min_range_m) || !std::isfinite(q.norm())) {
      ++counts.too_near;
      continue;
    }
    LidarPoint out = p;
    if (!sweep.has_ring) {
      const int ring = beams.ring_of(std::atan2(q.z(), horizontal - config.beam_origin_offset_m));
      if (ring < 0) {
        ++counts.no_beam;
        continue;
      }
      out.ring = static_cast<std::uint16_t>(ring);
    }
    if (!sweep.has_time) out.time = time_from_azimuth(std::atan2(q.y(), q.x()), config);
    highest_ring = std::max(highest_ring, out.ring);
    latest = std::max(latest, out.time);
    scan.points.push_back(out);
  }
  // The feature extractor reads each ring's returns in the order they come: firing order.
  std::stable_sort(scan.points.begin(), scan.points.end(),
                   [](const LidarPoint& a, const LidarPoint& b) { return a.time < b.time; });
  scan.beam_count = sweep.has_ring ? static_cast<std::uint16_t>(highest_ring + 1) : static_cast<std::uint16_t>(beams.beams());
  if (sweep.end_time > 0.0) {
    scan.end_time = sweep.end_time;
  } else {
    scan.end_time = sweep.start_time + (sweep.has_time ? static_cast<double>(latest) : config.sweep_period_s);
  }
  if (stats != nullptr) *stats = counts;
  return scan;
}

}  // namespace liod::drivers
