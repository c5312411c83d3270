#include "liod/speed_search.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "liod/angles.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {
namespace {

Eigen::Vector3d flat(const Eigen::Vector3d& p) { return {p.x(), p.y(), 0.0}; }

}  // namespace

std::vector<std::size_t> vertical_structure(const std::vector<Eigen::Vector3d>& points,
                                            const VerticalStructureParams& params) {
  struct HeightRange {
    double low = 0.0;
    double high = 0.0;
  };
  const double inverse = 1.0 / params.cell_m;
  std::unordered_map<VoxelKey, HeightRange, VoxelKeyHash> cells;
  cells.reserve(points.size());
  for (const auto& p : points) {
    const auto [it, inserted] = cells.try_emplace(voxel_of(flat(p), inverse), HeightRange{p.z(), p.z()});
    if (!inserted) {
      it->second.low = std::min(it->second.low, p.z());
      it->second.high = std::max(it->second.high, p.z());
    }
  }
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const HeightRange& cell = cells.at(voxel_of(flat(points[i]), inverse));
    if (cell.high - cell.low >= params.min_height_spread_m && points[i].z() - cell.low >= params.ground_clearance_m) {
      out.push_back(i);
    }
  }
  return out;
}

std::vector<std::size_t> off_along_track_lines(const std::vector<Eigen::Vector3d>& points,
                                               const Eigen::Vector2d& direction, const AlongTrackLineParams& params) {
  const double inverse = 1.0 / params.radius_m;
  std::unordered_map<VoxelKey, std::vector<std::size_t>, VoxelKeyHash> cells;
  cells.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) cells[voxel_of(flat(points[i]), inverse)].push_back(i);
  const Eigen::Vector2d along = direction.normalized();
  const double min_cos = std::cos(params.max_angle_deg * kDegToRad);
  const double radius_squared = params.radius_m * params.radius_m;
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d centre = points[i].head<2>();
    const VoxelKey key = voxel_of(flat(points[i]), inverse);
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    Eigen::Matrix2d outer = Eigen::Matrix2d::Zero();
    int count = 0;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        const auto it = cells.find({key.x + dx, key.y + dy, 0});
        if (it == cells.end()) continue;
        for (const auto j : it->second) {
          const Eigen::Vector2d d = points[j].head<2>() - centre;
          if (d.squaredNorm() > radius_squared) continue;
          sum += d;
          outer += d * d.transpose();
          ++count;
        }
      }
    }
    bool on_line = false;
    if (count >= 3) {
      const Eigen::Vector2d mean = sum / count;
      const Eigen::Matrix2d covariance = outer / count - mean * mean.transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(covariance);
      const double length = eigen.eigenvalues()(1);
      on_line = length >= params.min_length_std_m * params.min_length_std_m &&
                eigen.eigenvalues()(0) <= params.max_width_ratio * length &&
                std::abs(eigen.eigenvectors().col(1).dot(along)) >= min_cos;
    }
    if (!on_line) out.push_back(i);
  }
  return out;
}

FootprintOverlap::FootprintOverlap(const std::vector<Eigen::Vector3d>& reference, double radius)
    : radius_(radius), footprint_(radius, LocalMap::kMaxPointsPerVoxel, radius / 4.0) {
  std::vector<Eigen::Vector3d> flattened;
  flattened.reserve(reference.size());
  for (const auto& p : reference) flattened.push_back(flat(p));
  footprint_.add(flattened, 0);
}

double FootprintOverlap::score(const std::vector<Eigen::Vector3d>& query) const {
  std::array<Eigen::Vector3d, LocalMap::kMaxNeighbours> nearest;
  const double inverse_squared = 1.0 / (radius_ * radius_);
  double sum = 0.0;
  for (const auto& q : query) {
    const Eigen::Vector3d p = flat(q);
    if (footprint_.nearest(p, 1, radius_, nearest) == 1) {
      sum += std::max(0.0, 1.0 - (nearest[0] - p).squaredNorm() * inverse_squared);
    }
  }
  return sum;
}

std::vector<double> coarse_grid(const GridSearchParams& params) {
  std::vector<double> out;
  const int count = static_cast<int>(std::floor((params.max - params.min) / params.coarse_step + 1e-9)) + 1;
  for (int i = 0; i < count; ++i) out.push_back(params.min + i * params.coarse_step);
  return out;
}

GridSearchResult refine_around(const std::function<double(double)>& score, double centre, const GridSearchParams& params) {
  GridSearchResult result{centre, score(centre)};
  const int half = static_cast<int>(std::round(params.coarse_step / params.fine_step));
  for (int i = -half; i <= half; ++i) {
    if (i == 0) continue;
    const double x = centre + i * params.fine_step;
    const double s = score(x);
    if (s > result.score) result = {x, s};
  }
  return result;
}

namespace {

// The index of the highest interior local maximum of scores (both neighbours lower or equal, the
// first of equals) among the hypotheses at least min_distance from `from`.
std::optional<std::size_t> highest_local_maximum(const std::vector<double>& hypotheses, const std::vector<double>& scores,
                                                 double from, double min_distance) {
  std::optional<std::size_t> peak;
  for (std::size_t i = 1; i + 1 < scores.size(); ++i) {
    if (std::abs(hypotheses[i] - from) < min_distance || scores[i] < scores[i - 1] || scores[i] < scores[i + 1]) continue;
    if (!peak || scores[i] > scores[*peak]) peak = i;
  }
  return peak;
}

}  // namespace

std::optional<std::size_t> separate_peak(const std::vector<double>& hypotheses, const std::vector<double>& scores,
                                         double min_abs, double min_share) {
  if (scores.size() != hypotheses.size() || scores.size() < 3) return std::nullopt;
  const double highest = *std::max_element(scores.begin(), scores.end());
  const auto peak = highest_local_maximum(hypotheses, scores, 0.0, min_abs);
  if (!peak || !(scores[*peak] > 0.0) || scores[*peak] < min_share * highest) return std::nullopt;
  return peak;
}

bool stands_clear_of_aliases(const std::vector<double>& hypotheses, const std::vector<double>& scores, std::size_t best,
                             double min_separation, double min_ratio) {
  if (scores.size() != hypotheses.size() || best == 0 || best + 1 >= scores.size()) return false;
  const auto rival = highest_local_maximum(hypotheses, scores, hypotheses[best], min_separation);
  return !rival || scores[best] >= min_ratio * scores[*rival];
}

GridSearchResult grid_search(const std::function<double(double)>& score, const GridSearchParams& params) {
  GridSearchResult best{0.0, -std::numeric_limits<double>::infinity()};
  for (const double x : coarse_grid(params)) {
    const double s = score(x);
    if (s > best.score) best = {x, s};
  }
  if (!std::isfinite(best.score)) return {};
  return refine_around(score, best.value, params);
}

}  // namespace liod
