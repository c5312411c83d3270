#include "liod/speed_search.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

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

GridSearchResult grid_search(const std::function<double(double)>& score, const GridSearchParams& params) {
  std::vector<std::pair<double, double>> coarse;  // (x, score)
  const int coarse_count = static_cast<int>(std::floor((params.max - params.min) / params.coarse_step + 1e-9)) + 1;
  for (int i = 0; i < coarse_count; ++i) {
    const double x = params.min + i * params.coarse_step;
    coarse.emplace_back(x, score(x));
  }
  GridSearchResult result;
  if (coarse.empty()) return result;
  const auto best = std::max_element(coarse.begin(), coarse.end(),
                                     [](const auto& a, const auto& b) { return a.second < b.second; });
  result.value = best->first;
  result.score = best->second;
  const double centre = best->first;
  const int fine_half = static_cast<int>(std::round(params.coarse_step / params.fine_step));
  for (int i = -fine_half; i <= fine_half; ++i) {
    const double x = centre + i * params.fine_step;
    const double s = score(x);
    if (s > result.score) {
      result.value = x;
      result.score = s;
    }
  }
  return result;
}

}  // namespace liod
