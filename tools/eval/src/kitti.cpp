#include "liod/eval/kitti.hpp"

#include <algorithm>
#include <numbers>

namespace liod::eval {
namespace {

constexpr double kDegPer100mPerRadPerM = 180.0 / std::numbers::pi * 100.0;

/// The devkit's lastFrameFromSegmentLength: the first frame whose distance exceeds (strictly) the first
/// frame's + len. The devkit scans linearly; distances never decrease, so a binary search finds the same
/// frame, which matters at 200 Hz where a sequence has 10^5 frames.
std::optional<std::size_t> last_frame(const std::vector<double>& dist, std::size_t first, double len) {
  const auto begin = dist.begin() + static_cast<std::ptrdiff_t>(first);
  const auto it = std::upper_bound(begin, dist.end(), dist[first] + len);
  if (it == dist.end()) return std::nullopt;
  return static_cast<std::size_t>(it - dist.begin());
}

}  // namespace

KittiResult kitti_odometry_error(const Poses& gt, const Poses& est, const KittiOptions& options) {
  KittiResult r;
  r.options = options;
  const std::vector<double> dist = path_distances(gt);
  r.gt_length_m = dist.empty() ? 0.0 : dist.back();
  const std::size_t step = options.step == 0 ? 1 : options.step;

  for (std::size_t first = 0; first < gt.size(); first += step) {
    for (const double len : options.lengths_m) {
      const auto last = last_frame(dist, first, len);
      if (!last) continue;
      const Eigen::Isometry3d delta_gt = gt[first].inverse() * gt[*last];
      const Eigen::Isometry3d delta_est = est[first].inverse() * est[*last];
      const Eigen::Isometry3d error = delta_est.inverse() * delta_gt;
      r.segments.push_back({first, *last, len, error.translation().norm() / len,
                            rotation_angle(error.linear()) / len});
    }
  }

  double t_sum = 0.0;
  double r_sum = 0.0;
  for (const auto& s : r.segments) {
    t_sum += s.translation_ratio;
    r_sum += s.rotation_rad_per_m;
  }
  if (!r.segments.empty()) {
    const auto n = static_cast<double>(r.segments.size());
    r.translational_pct = t_sum / n * 100.0;
    r.rotational_deg_per_100m = r_sum / n * kDegPer100mPerRadPerM;
  }

  for (const double len : options.lengths_m) {
    KittiLengthResult l;
    l.length_m = len;
    double lt = 0.0;
    double lr = 0.0;
    for (const auto& s : r.segments) {
      if (s.length_m != len) continue;
      ++l.segments;
      lt += s.translation_ratio;
      lr += s.rotation_rad_per_m;
    }
    if (l.segments > 0) {
      const auto n = static_cast<double>(l.segments);
      l.translational_pct = lt / n * 100.0;
      l.rotational_deg_per_100m = lr / n * kDegPer100mPerRadPerM;
    }
    r.per_length.push_back(l);
  }
  return r;
}

}  // namespace liod::eval
