#include "liod/map_correspondence.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <limits>

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
  // The six distinct sums of the symmetric covariance, each added in the neighbours' order.
  double xx = 0.0, xy = 0.0, xz = 0.0, yy = 0.0, yz = 0.0, zz = 0.0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = pts[static_cast<std::size_t>(i)] - m.mean;
    xx += d.x() * d.x();
    xy += d.x() * d.y();
    xz += d.x() * d.z();
    yy += d.y() * d.y();
    yz += d.y() * d.z();
    zz += d.z() * d.z();
  }
  m.covariance << xx, xy, xz, xy, yy, yz, xz, yz, zz;
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

// An edge residual's normal when it is measured along the ray from the viewpoint: the ray's part
// across the edge's axis (across = I - axis axis^T), unit length; none for a ray along the axis.
std::optional<Eigen::Vector3d> across_ray(const Eigen::Matrix3d& across, const Eigen::Vector3d& query,
                                          const Eigen::Vector3d& viewpoint) {
  const Eigen::Vector3d normal = across * (query - viewpoint);
  if (normal.norm() < 1e-6) return std::nullopt;
  return normal.normalized();
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
  Eigen::Vector3d normal = eig.eigenvectors().col(0).normalized();
  double offset = -normal.dot(m.mean);
  for (int i = 0; i < n; ++i) {
    if (std::abs(normal.dot(nn[static_cast<std::size_t>(i)]) + offset) > params.max_plane_thickness_m) return std::nullopt;
  }
  if (!params.blind_along.isZero() &&
      (params.blind_ground || std::abs(normal.dot(params.up)) < params.wall_max_up_cosine)) {
    // The plane turned about its centroid until it is parallel to blind_along.
    const Eigen::Vector3d across = normal - normal.dot(params.blind_along) * params.blind_along;
    if (across.norm() < 0.5) return std::nullopt;  // facing that way: it would locate nothing else
    normal = across.normalized();
    offset = -normal.dot(m.mean);
  }
  // A plane fitted to n points with noise sigma has its offset at the centroid known to sigma^2/n
  // and its tilt about the in-plane axis e_i to sigma^2 / (n spread_i^2); at the query, the tilt
  // acts over the query's offset from the centroid (VoxelMap, Yuan et al. 2022, eq. 5-8, with an
  // isotropic point noise). Without it, a query at the edge of its neighbourhood (ahead of the
  // rings the last keyframes left on the ground) carries a normal that noise tilted towards the
  // direction of travel, and its residual pulls the scan back onto the keyframes' ring pattern.
  if (!params.fit_uncertainty) return LinearResidual{normal, offset};
  const Eigen::Vector3d from_centroid = query - m.mean;
  double variance_scale = 1.0 + 1.0 / n;
  for (int axis = 1; axis < 3; ++axis) {
    const double along = eig.eigenvectors().col(axis).dot(from_centroid);
    variance_scale += along * along / (n * ev(axis));
  }
  return LinearResidual{normal, offset, variance_scale};
}

std::vector<Eigen::Vector3d> post_axes(const std::vector<Eigen::Vector3d>& edges, const Eigen::Vector3d& viewpoint,
                                       const Eigen::Vector3d& up, double depth_m) {
  const Eigen::Matrix3d across_up = Eigen::Matrix3d::Identity() - up * up.transpose();
  std::vector<Eigen::Vector3d> axes;
  axes.reserve(edges.size());
  for (const auto& p : edges) {
    const auto ray = across_ray(across_up, p, viewpoint);
    axes.push_back(ray ? Eigen::Vector3d(p + depth_m * *ray) : p);
  }
  return axes;
}

std::optional<LinearResidual> post_correspondence(LocalMap::NeighbourSearch& axes, const Eigen::Vector3d& query,
                                                  const Eigen::Vector3d& up, const Eigen::Vector3d& viewpoint,
                                                  const PostParams& params) {
  const Eigen::Matrix3d across_up = Eigen::Matrix3d::Identity() - up * up.transpose();
  const auto normal = across_ray(across_up, query, viewpoint);
  if (!normal) return std::nullopt;  // looking straight down the post
  const Eigen::Vector3d query_axis = query + params.depth_m * *normal;
  std::array<Eigen::Vector3d, LocalMap::kMaxNeighbours> points;
  const int wanted = std::clamp(params.neighbours, 2, LocalMap::kMaxNeighbours);
  const int n = axes.nearest(query_axis, wanted, params.radius_m, points);
  if (n < wanted) return std::nullopt;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double lowest = std::numeric_limits<double>::infinity();
  double highest = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = points[static_cast<std::size_t>(i)];
    centroid += p;
    lowest = std::min(lowest, up.dot(p));
    highest = std::max(highest, up.dot(p));
    for (int j = 0; j < i; ++j) {
      if ((across_up * (p - points[static_cast<std::size_t>(j)])).norm() > params.max_width_m) return std::nullopt;
    }
  }
  if (highest - lowest < params.min_height_m) return std::nullopt;
  centroid /= n;
  // Residual n . (query + depth n - centroid): the query's axis estimate against the map's. The
  // axis is known to its points' scatter over n (as a plane's offset).
  return LinearResidual{*normal, params.depth_m - normal->dot(centroid), 1.0 + 1.0 / n};
}

std::optional<LinearResidual> line_correspondence(LocalMap::NeighbourSearch& map, const Eigen::Vector3d& query,
                                                  const CorrespondenceParams& params, const Eigen::Vector3d* viewpoint) {
  Neighbourhood nb;
  if (!find_neighbourhood(map, query, params, nb)) return std::nullopt;
  const auto& eig = nb.eig;
  const Moments& m = nb.moments;
  const Eigen::Vector3d ev = eig.eigenvalues();
  if (!(ev(2) > params.min_line_ratio * ev(1))) return std::nullopt;
  const Eigen::Vector3d direction = eig.eigenvectors().col(2).normalized();
  const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - direction * direction.transpose();
  Eigen::Vector3d normal;
  if (viewpoint != nullptr) {
    // Along the ray (its part across the line): where an edge point lies across the ray depends on
    // where the beam grazed the post or corner, which moves with the viewpoint by up to the
    // object's width and one azimuth step; its range hardly (docs/design.md, "Edge residual along the ray").
    const auto along_ray = across_ray(across, query, *viewpoint);
    if (!along_ray) return std::nullopt;  // a ray along the line: no range to it
    normal = *along_ray;
  } else {
    normal = across * (query - m.mean);
    if (normal.norm() < 1e-6) return LinearResidual{Eigen::Vector3d::Zero(), 0.0};
    normal.normalize();
  }
  if (!params.fit_uncertainty) return LinearResidual{normal, -normal.dot(m.mean)};
  // As for planes: the line's offset and direction are uncertain, the latter over the query's
  // distance along the line from the neighbours' centroid.
  const double along = direction.dot(query - m.mean);
  const int n = nb.count;
  return LinearResidual{normal, -normal.dot(m.mean), 1.0 + 1.0 / n + along * along / (n * ev(2))};
}

}  // namespace liod
