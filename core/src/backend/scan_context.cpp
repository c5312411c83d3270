#include "liod/backend/scan_context.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

namespace liod {

ScanContext make_scan_context(const std::vector<Eigen::Vector3f>& level_points, const ScanContextConfig& config) {
  ScanContext sc;
  sc.rings = config.rings;
  sc.sectors = config.sectors;
  sc.bins = Eigen::MatrixXf::Zero(config.rings, config.sectors);
  const double ring_width = config.max_range_m / config.rings;
  const double sector_width = 2.0 * std::numbers::pi / config.sectors;
  for (const auto& p : level_points) {
    const double range = std::hypot(double{p.x()}, double{p.y()});
    if (!(range < config.max_range_m) || !std::isfinite(p.z())) continue;
    const double azimuth = std::atan2(double{p.y()}, double{p.x()}) + std::numbers::pi;  // [0, 2 pi]
    const int ring = std::min(config.rings - 1, static_cast<int>(range / ring_width));
    const int sector = std::min(config.sectors - 1, static_cast<int>(azimuth / sector_width));
    const float height = static_cast<float>(std::max(0.0, double{p.z()} + config.height_offset_m));
    float& bin = sc.bins(ring, sector);
    bin = std::max(bin, height);
  }
  sc.sector_key = sc.bins.colwise().mean().transpose();
  return sc;
}

Eigen::Matrix3d level_from_body(const Eigen::Matrix3d& world_from_body) {
  const double yaw = std::atan2(world_from_body(1, 0), world_from_body(0, 0));
  return Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * world_from_body;
}

namespace {

// The mean cosine distance of the columns under one shift (1 when under half of them compare).
double shifted_distance(const ScanContext& query, const ScanContext& candidate, const Eigen::VectorXf& qn,
                        const Eigen::VectorXf& cn, int shift) {
  const int n = query.sectors;
  double sum = 0.0;
  int compared = 0;
  for (int c = 0; c < n; ++c) {
    const int d = (c + shift) % n;
    if (qn(c) <= 0.0F || cn(d) <= 0.0F) continue;
    sum += 1.0 - double{query.bins.col(c).dot(candidate.bins.col(d)) / (qn(c) * cn(d))};
    ++compared;
  }
  return 2 * compared >= n ? sum / compared : 1.0;
}

}  // namespace

ScanContextMatch match_scan_contexts(const ScanContext& query, const ScanContext& candidate) {
  ScanContextMatch best;
  const int n = query.sectors;
  if (n == 0 || candidate.sectors != n || candidate.rings != query.rings) return best;
  // The shifts whose sector keys differ least, then the full distance around each.
  constexpr int kShifts = 3;
  std::vector<std::pair<float, int>> by_key;
  by_key.reserve(static_cast<std::size_t>(n));
  for (int shift = 0; shift < n; ++shift) {
    float d = 0.0F;
    for (int c = 0; c < n; ++c) d += std::abs(query.sector_key(c) - candidate.sector_key((c + shift) % n));
    by_key.emplace_back(d, shift);
  }
  std::partial_sort(by_key.begin(), by_key.begin() + kShifts, by_key.end());
  const Eigen::VectorXf qn = query.bins.colwise().norm();
  const Eigen::VectorXf cn = candidate.bins.colwise().norm();
  for (int k = 0; k < kShifts; ++k) {
    for (int step = -1; step <= 1; ++step) {
      const int shift = (by_key[static_cast<std::size_t>(k)].second + step + n) % n;
      const double distance = shifted_distance(query, candidate, qn, cn, shift);
      if (distance < best.distance) {
        best.distance = distance;
        best.shift = shift;
      }
    }
  }
  const double yaw = 2.0 * std::numbers::pi * best.shift / n;
  best.yaw_rad = yaw > std::numbers::pi ? yaw - 2.0 * std::numbers::pi : yaw;
  return best;
}

}  // namespace liod
