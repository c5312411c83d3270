#include "liod/map_correspondence.hpp"

#include <Eigen/Eigenvalues>
#include <array>

namespace liod {
namespace {

struct Moments {
  Eigen::Vector3d mean;
  Eigen::Matrix3d covariance;
};

Moments moments(const std::array<Eigen::Vector3d, LocalMap::kMaxNeighbours>& pts, int n) {
  Moments m{Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()};
  for (int i = 0; i < n; ++i) m.mean += pts[static_cast<std::size_t>(i)];
  m.mean /= n;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = pts[static_cast<std::size_t>(i)] - m.mean;
    m.covariance += d * d.transpose();
  }
  m.covariance /= n;
  return m;
}

struct Neighbourhood {
  std::array<Eigen::Vector3d, LocalMap::kMaxNeighbours> points;
  int count = 0;
  Moments moments;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;  // eigenvalues ascending
};

// The query's map neighbours and their principal axes into nb, if it has enough of them (filled
// in place: the callers keep it on their stack rather than copy it out of an optional).
bool find_neighbourhood(LocalMap::NeighbourSearch& map, const Eigen::Vector3d& query, const CorrespondenceParams& params,
                        Neighbourhood& nb) {
  nb.count = map.nearest(query, params.neighbours, params.max_distance_m, nb.points);
  if (nb.count < params.neighbours) return false;
  nb.moments = moments(nb.points, nb.count);
  nb.eig.computeDirect(nb.moments.covariance);
  return true;
}

}  // namespace

std::optional<LinearResidual> plane_correspondence(LocalMap::NeighbourSearch& map, const Eigen::Vector3d& query,
                                                   const CorrespondenceParams& params) {
  Neighbourhood nb;
  if (!find_neighbourhood(map, query, params, nb)) return std::nullopt;
  const auto& eig = nb.eig;
  const auto& nn = nb.points;
  const int n = nb.count;
  const Moments& m = nb.moments;
  // Neighbours along one scan ring are nearly collinear: every plane through that line fits them,
  // so the normal would be arbitrary. Demand a real second dimension.
  const Eigen::Vector3d ev = eig.eigenvalues();
  if (ev(1) < params.min_plane_spread_ratio * params.min_plane_spread_ratio * ev(2)) return std::nullopt;
  const Eigen::Vector3d normal = eig.eigenvectors().col(0).normalized();
  const double offset = -normal.dot(m.mean);
  for (int i = 0; i < n; ++i) {
    if (std::abs(normal.dot(nn[static_cast<std::size_t>(i)]) + offset) > params.max_plane_thickness_m) return std::nullopt;
  }
  return LinearResidual{normal, offset};
}

std::optional<LinearResidual> line_correspondence(LocalMap::NeighbourSearch& map, const Eigen::Vector3d& query,
                                                  const CorrespondenceParams& params) {
  Neighbourhood nb;
  if (!find_neighbourhood(map, query, params, nb)) return std::nullopt;
  const auto& eig = nb.eig;
  const Moments& m = nb.moments;
  const Eigen::Vector3d ev = eig.eigenvalues();
  if (!(ev(2) > params.min_line_ratio * ev(1))) return std::nullopt;
  const Eigen::Vector3d direction = eig.eigenvectors().col(2).normalized();
  const Eigen::Vector3d off_line = (Eigen::Matrix3d::Identity() - direction * direction.transpose()) * (query - m.mean);
  const double distance = off_line.norm();
  if (distance < 1e-6) return LinearResidual{Eigen::Vector3d::Zero(), 0.0};
  const Eigen::Vector3d normal = off_line / distance;
  return LinearResidual{normal, -normal.dot(m.mean)};
}

}  // namespace liod
