#include "liod/backend/loop_closure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "liod/angles.hpp"
#include "liod/iterated_update.hpp"
#include "liod/local_map.hpp"
#include "liod/map_correspondence.hpp"
#include "liod/so3.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {
namespace {

// Nearest-neighbour distances below `cap` for many queries against one cloud: cells of size
// cap, so every neighbour closer than cap lies in the 27 cells around the query.
class NearestGrid {
 public:
  NearestGrid(const std::vector<Eigen::Vector3d>& points, double cap) : inverse_(1.0 / cap), cap_(cap) {
    grid_.reserve(points.size());
    for (const auto& p : points) grid_[voxel_of(p, inverse_)].push_back(p);
  }
  double distance(const Eigen::Vector3d& q) const {
    const VoxelKey c = voxel_of(q, inverse_);
    double best = cap_ * cap_;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid_.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == grid_.end()) continue;
          for (const auto& p : it->second) best = std::min(best, (p - q).squaredNorm());
        }
      }
    }
    return std::sqrt(best);
  }
  bool empty() const { return grid_.empty(); }

 private:
  double inverse_;
  double cap_;
  std::unordered_map<VoxelKey, std::vector<Eigen::Vector3d>, VoxelKeyHash> grid_;
};

double quantile_of(std::vector<double>& values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size()))) - (q > 0.0 ? 1 : 0);
  const auto index = std::min(values.size() - 1, k);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(index), values.end());
  return values[index];
}

double partial_directed(const std::vector<Eigen::Vector3d>& a, const NearestGrid& b, double q, double cap,
                        std::vector<double>& scratch) {
  if (a.empty() || b.empty()) return cap;
  scratch.clear();
  for (const auto& p : a) scratch.push_back(b.distance(p));
  return quantile_of(scratch, q);
}

}  // namespace

const char* to_string(LoopOutcome outcome) {
  switch (outcome) {
    case LoopOutcome::kAccepted: return "accepted";
    case LoopOutcome::kNoCandidate: return "no candidate";
    case LoopOutcome::kDissimilar: return "dissimilar";
    case LoopOutcome::kRegistrationFailed: return "registration failed";
    case LoopOutcome::kVerticalDisagreement: return "vertical disagreement";
    case LoopOutcome::kInconsistent: return "inconsistent with the graph";
  }
  return "?";
}

std::vector<std::size_t> loop_candidates(const std::vector<Eigen::Isometry3d>& poses, const std::vector<double>& times,
                                         std::size_t current, const BackendConfig& config, std::size_t limit) {
  std::vector<std::pair<double, std::size_t>> found;
  const Eigen::Vector3d c = poses[current].translation();
  for (std::size_t i = 0; i < current; ++i) {
    if (times[current] - times[i] < config.loop_time_gap_s) continue;
    Eigen::Vector3d d = poses[i].translation() - c;
    // The paper's 2D test ignores z, where odometry drifts most; 3D is the ablation.
    if (config.loop_distance == LoopDistance::k2D) d.z() = 0.0;
    const double distance = d.norm();
    if (distance <= config.loop_radius_m) found.emplace_back(distance, i);
  }
  std::sort(found.begin(), found.end());
  // Keep candidates from distinct passes: neighbours of an already kept candidate (within the
  // sub-map span) would only repeat the same test.
  std::vector<std::size_t> out;
  for (const auto& [distance, index] : found) {
    bool near_kept = false;
    for (auto k : out) {
      near_kept = near_kept || (index > k ? index - k : k - index) <= static_cast<std::size_t>(config.submap_keyframes);
    }
    if (!near_kept) out.push_back(index);
    if (out.size() >= limit) break;
  }
  return out;
}

double partial_directed_hausdorff(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
                                  double quantile, double cap) {
  const NearestGrid grid(b, cap);
  std::vector<double> scratch;
  return partial_directed(a, grid, quantile, cap, scratch);
}

double partial_hausdorff(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, double quantile,
                         double cap) {
  return std::max(partial_directed_hausdorff(a, b, quantile, cap), partial_directed_hausdorff(b, a, quantile, cap));
}

namespace {

// Points of structure: more than kMinHeight above the lowest point of their x-y cell. The
// ground matches the ground of any other place, so with it in the test a partial Hausdorff
// distance would call most pairs of places similar; structure (walls, poles, cars) is what
// tells places apart. Local per cell, so that slopes are not mistaken for structure.
std::vector<Eigen::Vector3d> structure_points(const std::vector<Eigen::Vector3d>& cloud) {
  constexpr double kCell = 2.0;
  constexpr double kMinHeight = 0.4;
  constexpr std::size_t kMinPoints = 30;
  std::unordered_map<VoxelKey, double, VoxelKeyHash> lowest;
  auto cell = [&](const Eigen::Vector3d& p) {
    return VoxelKey{static_cast<std::int32_t>(std::floor(p.x() / kCell)), static_cast<std::int32_t>(std::floor(p.y() / kCell)), 0};
  };
  for (const auto& p : cloud) {
    auto [it, inserted] = lowest.try_emplace(cell(p), p.z());
    if (!inserted) it->second = std::min(it->second, p.z());
  }
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : cloud) {
    if (p.z() > lowest[cell(p)] + kMinHeight) out.push_back(p);
  }
  return out.size() >= kMinPoints ? out : cloud;
}

}  // namespace

namespace {

struct Hypothesis {
  double x = 0, y = 0, z = 0, yaw = 0;
};

// The alignment of `base` (the scan's structure points relative to `centre`) on the sub-map that
// minimises the partial Hausdorff distance. Coarse to fine: x-y on a 1 m grid (the clouds are ~1 m
// voxels), then yaw, then z in steps of half the vertical limit (a larger z offset would be
// rejected later anyway), then x-y on a 0.5 m grid around the best.
Hypothesis search_alignment(const std::vector<Eigen::Vector3d>& base, const Eigen::Vector3d& centre,
                            const NearestGrid& grid, double cap, const BackendConfig& config) {
  const double q = config.similarity_quantile;
  std::vector<double> scratch;
  std::vector<Eigen::Vector3d> moved(base.size());
  auto score = [&](const Hypothesis& h) {
    const Eigen::Matrix3d r = Eigen::AngleAxisd(h.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d t = centre + Eigen::Vector3d(h.x, h.y, h.z);
    for (std::size_t i = 0; i < base.size(); ++i) moved[i] = r * base[i] + t;
    // Ties go to the smaller offset (the odometry's guess is the prior).
    return partial_directed(moved, grid, q, cap, scratch) + 1e-6 * std::hypot(h.x, h.y, h.z);
  };
  Hypothesis best;
  double best_score = score(best);
  auto consider = [&](const Hypothesis& h) {
    const double d = score(h);
    if (d < best_score) {
      best_score = d;
      best = h;
    }
  };
  const int nxy = static_cast<int>(std::floor(config.similarity_search_m));
  for (int ix = -nxy; ix <= nxy; ++ix) {
    for (int iy = -nxy; iy <= nxy; ++iy) consider({static_cast<double>(ix), static_cast<double>(iy), 0.0, 0.0});
  }
  const double yaw_limit = config.similarity_search_yaw_deg * kDegToRad;
  const Hypothesis after_xy = best;
  for (int k = -2; k <= 2; ++k) {
    if (k != 0 && yaw_limit > 0.0) consider({after_xy.x, after_xy.y, 0.0, yaw_limit * k / 2.0});
  }
  const Hypothesis after_yaw = best;
  for (int k : {-1, 1}) consider({after_yaw.x, after_yaw.y, 0.5 * config.max_vertical_m * k, after_yaw.yaw});
  const Hypothesis after_z = best;
  for (int ix = -1; ix <= 1; ++ix) {
    for (int iy = -1; iy <= 1; ++iy) {
      if (ix != 0 || iy != 0) consider({after_z.x + 0.5 * ix, after_z.y + 0.5 * iy, after_z.z, after_z.yaw});
    }
  }
  return best;
}

}  // namespace

SimilarityResult similarity_search(const std::vector<Eigen::Vector3d>& cloud_body, const Eigen::Isometry3d& guess,
                                   const std::vector<Eigen::Vector3d>& submap_world,
                                   const std::vector<Eigen::Vector3d>& candidate_world, const BackendConfig& config) {
  const double q = config.similarity_quantile;
  // Distances beyond twice the threshold only need to be known as "too far".
  const double cap = std::max(2.0 * config.similarity_threshold_m, 0.5);
  const std::vector<Eigen::Vector3d> submap = structure_points(submap_world);
  const NearestGrid grid(submap, cap);
  std::vector<double> scratch;
  const Eigen::Vector3d centre = guess.translation();

  // The scan's structure in the world at the guess, relative to the keyframe's position.
  std::vector<Eigen::Vector3d> world(cloud_body.size());
  for (std::size_t i = 0; i < cloud_body.size(); ++i) world[i] = guess * cloud_body[i];
  const std::vector<Eigen::Vector3d> scan = structure_points(world);
  // The search scores a deterministic subset (every k-th point): enough for a quantile.
  constexpr std::size_t kSearchPoints = 400;
  const std::size_t stride = std::max<std::size_t>(1, scan.size() / kSearchPoints);
  std::vector<Eigen::Vector3d> base;
  for (std::size_t i = 0; i < scan.size(); i += stride) base.push_back(scan[i] - centre);
  const Hypothesis best = search_alignment(base, centre, grid, cap, config);

  SimilarityResult result;
  Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
  delta.linear() = Eigen::AngleAxisd(best.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  delta.translation() = centre + Eigen::Vector3d(best.x, best.y, best.z) - delta.linear() * centre;  // about the keyframe
  result.aligned = delta * guess;

  // Both directions at the best alignment, on all structure points: the scan explained by the
  // sub-map, and the candidate keyframe explained by the scan. The reverse direction uses the
  // candidate alone, not the sub-map, which covers far more than one scan sees; both are single
  // scans from nearby places, cropped to the current scan's horizontal reach.
  std::vector<Eigen::Vector3d> aligned;
  aligned.reserve(scan.size());
  double reach = 0.0;
  for (const auto& p : scan) {
    aligned.push_back(delta * p);
    reach = std::max(reach, (aligned.back() - result.aligned.translation()).head<2>().norm());
  }
  std::vector<Eigen::Vector3d> cropped;
  for (const auto& p : structure_points(candidate_world)) {
    if ((p - result.aligned.translation()).head<2>().norm() <= reach) cropped.push_back(p);
  }
  result.forward_m = partial_directed(aligned, grid, q, cap, scratch);
  result.backward_m = partial_directed(cropped, NearestGrid(aligned, cap), q, cap, scratch);
  result.distance_m = std::max(result.forward_m, result.backward_m);
  return result;
}

}  // namespace liod
