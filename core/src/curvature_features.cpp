#include "liod/curvature_features.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace liod {
namespace {

// sum over m in [k - kHalf, k + kHalf], m != k, of (X_k - X_m), added in that order. The half
// width is a template argument so that the loops unroll (no per-step loop or m == k test).
template <int kHalf>
Eigen::Vector3f summed_differences(const float* x, const float* y, const float* z, int k) {
  float sx = 0.0F;
  float sy = 0.0F;
  float sz = 0.0F;
  for (int m = k - kHalf; m < k; ++m) {
    sx += x[k] - x[m];
    sy += y[k] - y[m];
    sz += z[k] - z[m];
  }
  for (int m = k + 1; m <= k + kHalf; ++m) {
    sx += x[k] - x[m];
    sy += y[k] - y[m];
    sz += z[k] - z[m];
  }
  return {sx, sy, sz};
}

// The curvature (the paper's c, eq. 1) of ring positions [begin, end), which share the half width
// kHalf: one loop over the positions, so that the compiler computes several of them at once. Each
// position's sum is still added in its own order (m ascending), so the values do not change.
template <int kHalf>
void ring_curvatures(const float* __restrict x, const float* __restrict y, const float* __restrict z,
                     const float* __restrict range, int begin, int end, float* __restrict curvature) {
  for (int k = begin; k < end; ++k) {
    const Eigen::Vector3f sum = summed_differences<kHalf>(x, y, z, k);
    curvature[k] = std::sqrt(sum.x() * sum.x() + sum.y() * sum.y() + sum.z() * sum.z()) /
                   (static_cast<float>(2 * kHalf) * range[k]);
  }
}

}  // namespace

Eigen::Vector3f surface_end_shift(const Eigen::Vector3f& end, const Eigen::Vector3f& previous, double extrapolation) {
  // Below these the step is the face-on spacing and its range noise (a couple of centimetres a
  // return): moving a post's silhouette point by half of it adds noise, not accuracy. 5x the
  // face-on step is grazing below 11.5 deg (the extractor drops surface ends met under 10 deg as
  // parallel to the beam): only steep steps, such as a wall's end seen along it, are moved
  // (docs/design.md, "Surface ends at grazing incidence").
  constexpr float kMinGrazingStepRatio = 5.0F;
  constexpr float kMinExtrapolatedStepM = 0.05F;
  const float end_range = end.norm();
  const float previous_range = previous.norm();
  if (extrapolation <= 0.0 || end_range <= 0.0F || previous_range <= 0.0F) return Eigen::Vector3f::Zero();
  const Eigen::Vector3f step = end - previous;
  const float face_on_step = end_range * (end / end_range - previous / previous_range).norm();
  const float length = step.norm();
  if (length <= kMinExtrapolatedStepM || length <= kMinGrazingStepRatio * face_on_step) return Eigen::Vector3f::Zero();
  return static_cast<float>(extrapolation) * step;
}

constexpr float kMaxExcessDepthM = 0.02F;  // range noise and sampling

std::optional<Eigen::Vector3f> narrow_run_axis(const float* x, const float* y, const float* z, int first, int last) {
  if (last <= first) return std::nullopt;
  Eigen::Vector2f towards = Eigen::Vector2f::Zero();
  float height = 0.0F;
  for (int j = first; j <= last; ++j) {
    towards += Eigen::Vector2f(x[j], y[j]);
    height += z[j];
  }
  const int count = last - first + 1;
  height /= static_cast<float>(count);
  if (towards.norm() < 1e-6F) return std::nullopt;
  const Eigen::Vector2f along = towards.normalized();
  const Eigen::Vector2f across(-along.y(), along.x());
  float lowest = std::numeric_limits<float>::infinity();
  float highest = -std::numeric_limits<float>::infinity();
  float nearest = std::numeric_limits<float>::infinity();
  float farthest = -std::numeric_limits<float>::infinity();
  for (int j = first; j <= last; ++j) {
    const Eigen::Vector2f q(x[j], y[j]);
    lowest = std::min(lowest, across.dot(q));
    highest = std::max(highest, across.dot(q));
    nearest = std::min(nearest, along.dot(q));
    farthest = std::max(farthest, along.dot(q));
  }
  const float width = (highest - lowest) * static_cast<float>(count) / static_cast<float>(count - 1);
  // A compact section shows no more depth than width (a square's or a circle's visible side at
  // most as much); a sliver of a long face seen at grazing incidence (a rail's band between the
  // ground's returns, which moves with the viewpoint) shows far more.
  if (farthest - nearest > width + kMaxExcessDepthM) return std::nullopt;
  const Eigen::Vector2f axis = (nearest + 0.5F * width) * along + 0.5F * (lowest + highest) * across;
  return Eigen::Vector3f(axis.x(), axis.y(), height);
}

int curvature_neighbourhood_size(double range_m, CurvatureNeighbourhood mode) {
  if (mode == CurvatureNeighbourhood::kFixed) return 10;
  if (range_m <= 10.0) return 10;
  if (range_m <= 20.0) return 8;
  if (range_m <= 30.0) return 6;
  return 4;
}

void FeatureExtractor::extract(const Scan& scan, ScanFeatures& out) {
  out.edges.clear();
  out.planes.clear();
  out.plane_curvatures.clear();
  out.edge_shifts.clear();
  const std::size_t beams = std::max<std::size_t>(scan.beam_count, 1);
  if (rings_.size() < beams) rings_.resize(beams);
  for (auto& ring : rings_) ring.clear();
  range_.resize(scan.points.size());
  const float min_range = static_cast<float>(params_.min_range_m);
  const float max_range = static_cast<float>(params_.max_range_m);
  for (std::uint32_t i = 0; i < scan.points.size(); ++i) {
    const auto& p = scan.points[i];
    const float r = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    range_[i] = r;
    if (!std::isfinite(r) || r < min_range || r > max_range || p.ring >= rings_.size()) continue;
    if (params_.self_crop && r <= self_crop_reach_ && params_.self_crop->contains(Eigen::Vector3f(p.x, p.y, p.z))) {
      continue;
    }
    rings_[p.ring].push_back(i);
  }
  for (std::size_t ring_id = 0; ring_id < rings_.size(); ++ring_id) process_ring(scan, ring_id, out);
}

bool FeatureExtractor::surface_continues(const Scan& scan, std::size_t ring_id, int step, const Eigen::Vector2f& end,
                                         const Eigen::Vector2f& inner, float end_time, int side) const {
  const auto other = static_cast<std::ptrdiff_t>(ring_id) + step;
  if (other < 0 || other >= static_cast<std::ptrdiff_t>(rings_.size())) return false;
  const Eigen::Vector2f along = end - inner;
  if (along.norm() < 1e-3F) return false;
  const Eigen::Vector2f direction = along.normalized();
  const Eigen::Vector2f normal(-direction.y(), direction.x());
  const auto tolerance = static_cast<float>(params_.crossing_edge_tolerance_m);
  // Two to four firings on: one firing past the edge the next ring may still meet the silhouette
  // of a vertical post (the beams of one firing are fired a few microseconds apart).
  const float a = end_time + static_cast<float>(side) * 1.5F * kFiringPeriodS;
  const float b = end_time + static_cast<float>(side) * 4.5F * kFiringPeriodS;
  const auto& ring = rings_[static_cast<std::size_t>(other)];
  auto it = std::lower_bound(ring.begin(), ring.end(), std::min(a, b),
                             [&](std::uint32_t i, float t) { return scan.points[i].time < t; });
  for (; it != ring.end() && scan.points[*it].time <= std::max(a, b); ++it) {
    const Eigen::Vector2f q(scan.points[*it].x, scan.points[*it].y);
    if ((q - end).dot(direction) > 0.0F && std::abs((q - end).dot(normal)) < tolerance) return true;
  }
  return false;
}

void FeatureExtractor::gather_ring(const Scan& scan, const std::vector<std::uint32_t>& ring) {
  const std::size_t n = ring.size();
  ring_x_.resize(n);
  ring_y_.resize(n);
  ring_z_.resize(n);
  ring_time_.resize(n);
  ring_range_.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const LidarPoint& p = scan.points[ring[k]];
    ring_x_[k] = p.x;
    ring_y_[k] = p.y;
    ring_z_[k] = p.z;
    ring_time_[k] = p.time;
    ring_range_[k] = range_[ring[k]];
  }
}

void FeatureExtractor::process_ring(const Scan& scan, std::size_t ring_id, ScanFeatures& out) {
  const std::vector<std::uint32_t>& ring = rings_[ring_id];
  const int n = static_cast<int>(ring.size());
  if (n < 2 * kMaxHalf + 1) return;
  excluded_.assign(static_cast<std::size_t>(n), 0);
  gather_ring(scan, ring);
  mark_time_gaps(n);
  exclude_occluded_and_parallel(n);
  ring_curvatures_by_range(n);
  // Per sector: the sharpest points become edges (spread out), the flattest ones planes.
  const int sectors = std::max(1, params_.sectors_per_ring);
  for (int s = 0; s < sectors; ++s) pick_sector(scan, ring_id, s * n / sectors, (s + 1) * n / sectors, out);
}

void FeatureExtractor::mark_time_gaps(int n) {
  // Missing returns leave gaps in time; a window across a gap mixes distant surfaces.
  // Consecutive firings of one beam are 55.6 us apart at 10 Hz; allow a few missing.
  // gaps_before_[k]: how many of the steps k' -> k' + 1 with k' < k are gaps, so that a window's
  // test is one difference instead of a loop over its steps.
  constexpr float kMaxFiringGap = 4.0F * kFiringPeriodS;
  gaps_before_.resize(static_cast<std::size_t>(n));
  gaps_before_[0] = 0;
  for (int k = 0; k + 1 < n; ++k) {
    const bool gap = ring_time_[static_cast<std::size_t>(k) + 1] - ring_time_[static_cast<std::size_t>(k)] > kMaxFiringGap;
    gaps_before_[static_cast<std::size_t>(k) + 1] = gaps_before_[static_cast<std::size_t>(k)] + (gap ? 1 : 0);
  }
}

bool FeatureExtractor::across_gap(int a, int b) const {
  return gaps_before_[static_cast<std::size_t>(std::max(a, b))] != gaps_before_[static_cast<std::size_t>(std::min(a, b))];
}

void FeatureExtractor::exclude_occluded_and_parallel(int n) {
  const float* range = ring_range_.data();
  // Occlusion: at a range jump, the far side's points are hidden behind the near object and
  // their apparent edge moves with the viewpoint, so they are unreliable features.
  // The jumps are found first, several positions at a time (without a branch), then the few
  // there are handled.
  const float occlusion_jump = static_cast<float>(params_.occlusion_jump_m);
  range_jumps_.resize(static_cast<std::size_t>(n));
  std::uint8_t* jumps = range_jumps_.data();
  for (int k = 0; k + 1 < n; ++k) {
    const float r0 = range[k];
    const float r1 = range[k + 1];
    const float jump = occlusion_jump * std::max(1.0F, std::min(r0, r1) / 10.0F);
    jumps[k] = static_cast<std::uint8_t>(std::abs(r0 - r1) > jump);
  }
  for (int k = 0; k + 1 < n; ++k) {
    if (jumps[k]) {
      if (range[k] > range[k + 1]) {
        for (int m = std::max(0, k - kMaxHalf + 1); m <= k; ++m) excluded_[static_cast<std::size_t>(m)] = 1;
      } else {
        for (int m = k + 1; m <= std::min(n - 1, k + kMaxHalf); ++m) excluded_[static_cast<std::size_t>(m)] = 1;
      }
    }
  }
  // Beams nearly parallel to the surface: both neighbours' ranges differ a lot from this one.
  std::uint8_t* excluded = excluded_.data();
  for (int k = 1; k + 1 < n; ++k) {  // without a branch, several positions at a time
    const float r = range[k];
    const bool parallel = (std::abs(range[k - 1] - r) > 0.02F * r) & (std::abs(range[k + 1] - r) > 0.02F * r);
    excluded[k] = static_cast<std::uint8_t>(excluded[k] | static_cast<std::uint8_t>(parallel));
  }
}

void FeatureExtractor::ring_curvatures_by_range(int n) {
  const float* x = ring_x_.data();
  const float* y = ring_y_.data();
  const float* z = ring_z_.data();
  const float* range = ring_range_.data();
  ring_curvature_.assign(static_cast<std::size_t>(n), std::numeric_limits<float>::quiet_NaN());
  // Runs of positions whose range gives the same neighbourhood: along a ring the range changes
  // smoothly, so the runs are long.
  auto half_at = [&](int k) { return curvature_neighbourhood_size(range[k], params_.neighbourhood) / 2; };
  float* curvature = ring_curvature_.data();
  for (int begin = kMaxHalf; begin < n - kMaxHalf;) {
    const int half = half_at(begin);
    int end = begin + 1;
    while (end < n - kMaxHalf && half_at(end) == half) ++end;
    switch (half) {
      case 5: ring_curvatures<5>(x, y, z, range, begin, end, curvature); break;
      case 4: ring_curvatures<4>(x, y, z, range, begin, end, curvature); break;
      case 3: ring_curvatures<3>(x, y, z, range, begin, end, curvature); break;
      default: ring_curvatures<2>(x, y, z, range, begin, end, curvature); break;
    }
    for (int k = begin; k < end; ++k) {
      if (gaps_before_[static_cast<std::size_t>(k + half)] != gaps_before_[static_cast<std::size_t>(k - half)]) {
        curvature[k] = std::numeric_limits<float>::quiet_NaN();
      }
    }
    begin = end;
  }
}

Eigen::Vector3f FeatureExtractor::surface_end_step(int k, int n) const {
  // An edge whose range jumps beyond it on one side ends the surface on the other: its shift
  // towards that end, from the ring's previous return on the surface (no jump or missing return
  // between the two).
  const float* x = ring_x_.data();
  const float* y = ring_y_.data();
  const float* z = ring_z_.data();
  const float* range = ring_range_.data();
  const std::uint8_t* jumps = range_jumps_.data();
  int previous = -1;
  if (k + 1 < n && k > 0 && jumps[k] && range[k] < range[k + 1] && !jumps[k - 1]) previous = k - 1;
  if (k > 0 && k + 1 < n && jumps[k - 1] && range[k] < range[k - 1] && !jumps[k]) previous = k + 1;
  if (previous < 0 || across_gap(k, previous)) return Eigen::Vector3f::Zero();
  return surface_end_shift(Eigen::Vector3f(x[k], y[k], z[k]), Eigen::Vector3f(x[previous], y[previous], z[previous]),
                           params_.surface_end_extrapolation);
}

std::optional<Eigen::Vector3f> FeatureExtractor::post_run_shift(int k, int n) const {
  // An edge that ends a narrow run standing out before both of its neighbours (a post, a pole):
  // post_depth_m before the run's axis, along the horizontal ray, instead of where the return was.
  constexpr int kMaxRunReturns = 40;
  constexpr int kMinRunReturns = 3;
  const float* x = ring_x_.data();
  const float* y = ring_y_.data();
  const float* z = ring_z_.data();
  const float* range = ring_range_.data();
  const std::uint8_t* jumps = range_jumps_.data();
  // The run of returns around k without a range jump, k at one of its ends, both ends nearer
  // than the returns beyond them.
  int first = k;
  while (first > 0 && k - first < kMaxRunReturns - 1 && !jumps[first - 1]) --first;
  int last = k;
  while (last + 1 < n && last - k < kMaxRunReturns - 1 && !jumps[last]) ++last;
  const bool stands_out = first > 0 && jumps[first - 1] && range[first] < range[first - 1] && last + 1 < n &&
                          jumps[last] && range[last] < range[last + 1];
  if (!stands_out || (k != first && k != last) || last < first + kMinRunReturns - 1 ||
      gaps_before_[static_cast<std::size_t>(last)] != gaps_before_[static_cast<std::size_t>(first)]) {
    return std::nullopt;
  }
  const Eigen::Vector3f a(x[first], y[first], z[first]);
  const Eigen::Vector3f b(x[last], y[last], z[last]);
  if ((a - b).norm() > static_cast<float>(params_.post_max_width_m)) return std::nullopt;
  const auto axis = narrow_run_axis(x, y, z, first, last);
  if (!axis) return std::nullopt;
  const Eigen::Vector3f along = Eigen::Vector3f(axis->x(), axis->y(), 0.0F).normalized();
  return Eigen::Vector3f(*axis - static_cast<float>(params_.post_depth_m) * along - Eigen::Vector3f(x[k], y[k], z[k]));
}

bool FeatureExtractor::crosses_border(const Scan& scan, std::size_t ring_id, int k, int n) const {
  // An edge where the ring runs off a surface across a horizontal border: beyond it the ring
  // reaches farther, and the next ring up or down carries the surface on past it.
  constexpr int kCrossingBaseline = 6;  // returns back along the run for the surface's direction
  const float* x = ring_x_.data();
  const float* y = ring_y_.data();
  const float* range = ring_range_.data();
  const std::uint8_t* jumps = range_jumps_.data();
  for (const int side : {1, -1}) {
    // The surface's last return: k or one of the next two towards `side`, where the ring then
    // reaches farther (a jump, or a surface behind within the jump's threshold).
    int end = -1;
    for (int j = k; j != k + 3 * side && j + side >= 0 && j + side < n; j += side) {
      if (range[j + side] > range[j] * 1.02F) {
        end = j;
        break;
      }
    }
    if (end < 0) continue;
    int inner = end;
    while (inner - side >= 0 && inner - side < n && std::abs(inner - end) < kCrossingBaseline &&
           !jumps[std::min(inner, inner - side)]) {
      inner -= side;
    }
    if (inner == end) continue;
    const Eigen::Vector2f last(x[end], y[end]);
    const Eigen::Vector2f before(x[inner], y[inner]);
    const float t = ring_time_[static_cast<std::size_t>(end)];
    if (surface_continues(scan, ring_id, 1, last, before, t, side) ||
        surface_continues(scan, ring_id, -1, last, before, t, side)) {
      return true;
    }
  }
  return false;
}

void FeatureExtractor::pick_sector(const Scan& scan, std::size_t ring_id, int begin, int end, ScanFeatures& out) {
  const std::vector<std::uint32_t>& ring = rings_[ring_id];
  const int n = static_cast<int>(ring.size());
  order_.clear();
  for (int k = begin; k < end; ++k) {
    const float c = ring_curvature_[static_cast<std::size_t>(k)];
    if (!std::isnan(c) && !excluded_[static_cast<std::size_t>(k)]) order_.push_back({c, static_cast<std::uint32_t>(k)});
  }
  std::sort(order_.begin(), order_.end(), [](const Candidate& a, const Candidate& b) { return a.curvature > b.curvature; });
  int picked = 0;
  for (const Candidate& candidate : order_) {
    if (picked >= params_.max_edges_per_sector) break;
    if (candidate.curvature <= static_cast<float>(params_.edge_curvature)) break;
    const std::uint32_t k = candidate.position;
    if (excluded_[k]) continue;
    if (params_.crossing_edge_tolerance_m <= 0.0 || !crosses_border(scan, ring_id, static_cast<int>(k), n)) {
      out.edges.push_back(ring[k]);
      const auto on_post = params_.post_max_width_m > 0.0 ? post_run_shift(static_cast<int>(k), n) : std::nullopt;
      out.edge_shifts.push_back(on_post ? *on_post : surface_end_step(static_cast<int>(k), n));
      ++picked;
    }
    // Neighbours of an edge would duplicate it (of a dropped one, stand in for it).
    const int lo = std::max(0, static_cast<int>(k) - kMaxHalf);
    const int hi = std::min(n - 1, static_cast<int>(k) + kMaxHalf);
    for (int m = lo; m <= hi; ++m) excluded_[static_cast<std::size_t>(m)] = 1;
  }
  for (const Candidate& candidate : order_) {
    if (candidate.curvature < static_cast<float>(params_.plane_curvature) && !excluded_[candidate.position]) {
      out.planes.push_back(ring[candidate.position]);
      out.plane_curvatures.push_back(candidate.curvature);
    }
  }
}

}  // namespace liod
