#include "liod/iterated_update.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>

#include "liod/so3.hpp"

namespace liod {

namespace {

struct Normal6 {
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();  // sum w H^T H
  Eigen::Matrix<double, 6, 1> gradient = Eigen::Matrix<double, 6, 1>::Zero(); // sum w H^T r
  double squared_error = 0.0;
  int count = 0;
};

// Huber weight: residuals beyond k sigma count linearly, so a bad match cannot dominate.
double huber_weight(double r, double k) {
  const double a = std::abs(r);
  return a <= k ? 1.0 : k / a;
}

using Correspondences = std::vector<std::optional<LinearResidual>>;

// The points in the world at pose x, into `world` (reused from iteration to iteration).
void to_world(const std::vector<Eigen::Vector3d>& points_body, const NavState& x, std::vector<Eigen::Vector3d>& world) {
  world.resize(points_body.size());
  for (std::size_t i = 0; i < points_body.size(); ++i) world[i] = x.to_world(points_body[i]);
}

// Every point's correspondence (points_world: at the current pose). The points are taken voxel
// by voxel (sorted by their map voxel), so that neighbouring queries share the map look-ups of
// one NeighbourSearch; each answer still goes to its own point, so the sums over them keep
// their order.
template <typename Correspond>
void search_correspondences(const std::vector<Eigen::Vector3d>& points_world, const LocalMap& map,
                            const CorrespondenceParams& params, Correspond correspond, Correspondences& cache) {
  cache.resize(points_world.size());
  LocalMap::NeighbourSearch neighbours(map);
  for (const std::uint32_t i : map.voxel_order(points_world)) {
    cache[i] = correspond(neighbours, points_world[i], params);
  }
}

// The correspondence parameters at pose x: planes_blind_along_body turned into the world.
CorrespondenceParams correspondence_at(const NavState& x, const UpdateParams& params) {
  CorrespondenceParams p = params.correspondence;
  if (!params.planes_blind_along_body) return p;
  p.blind_along = (x.rotation * *params.planes_blind_along_body).normalized();
  p.blind_ground = params.ground_blind_too;
  p.up = -x.gravity.normalized();
  return p;
}

// With `search` the map is queried afresh; otherwise the planes/lines found last time are kept
// (re-linearised at the new pose), which is what makes later iterations cheap.
// points_world: points_body at pose x (to_world), a buffer shared with the search.
template <typename Correspond>
void accumulate(const std::vector<Eigen::Vector3d>& points_body, const NavState& x,
                std::vector<Eigen::Vector3d>& points_world, const LocalMap& map, const UpdateParams& params,
                Correspond correspond, bool search, Correspondences& cache, Normal6& eq) {
  const double k = 2.0 * params.lidar_noise_m;
  to_world(points_body, x, points_world);
  if (search) search_correspondences(points_world, map, correspondence_at(x, params), correspond, cache);
  for (std::size_t i = 0; i < points_body.size(); ++i) {
    const Eigen::Vector3d& pb = points_body[i];
    const Eigen::Vector3d& q = points_world[i];
    const auto& residual = cache[i];
    if (!residual || residual->normal.isZero()) continue;
    const double r = residual->evaluate(q);
    // d q / d dtheta = -R [pb]x  (right perturbation), d q / d p = I.
    Eigen::Matrix<double, 1, 6> h;
    h.head<3>() = -residual->normal.transpose() * x.rotation * so3::hat(pb);
    h.tail<3>() = residual->normal.transpose();
    const double w = huber_weight(r / std::sqrt(residual->variance_scale), k) / residual->variance_scale;
    eq.hessian.noalias() += w * h.transpose() * h;
    eq.gradient.noalias() += w * h.transpose() * r;
    eq.squared_error += r * r;
    ++eq.count;
  }
}

// Adds the vehicle constraint u^T R^T v = 0 to the MAP normal equations. With R = R^ Exp(dtheta),
// R^T v = (I - [dtheta]x) R^T v, so d/d dtheta = u^T [v_b]x and d/d dv = u^T R^T.
void add_vertical_velocity_constraint(const NavState& x, const UpdateParams& params, StateCovariance& information,
                                      StateVector& rhs) {
  const Eigen::Vector3d velocity_body = x.rotation.transpose() * x.velocity;
  Eigen::Matrix<double, 1, kStateDim> h = Eigen::Matrix<double, 1, kStateDim>::Zero();
  h.segment<3>(0) = params.vertical_axis.transpose() * so3::hat(velocity_body);
  h.segment<3>(6) = params.vertical_axis.transpose() * x.rotation.transpose();
  const double r = params.vertical_axis.dot(velocity_body);
  const double inv_var = 1.0 / (params.vertical_velocity_std * params.vertical_velocity_std);
  information.noalias() += inv_var * h.transpose() * h;
  rhs.noalias() -= inv_var * h.transpose() * r;
}

}  // namespace

UpdateResult iterated_update(const NavState& prior, const StateCovariance& prior_covariance,
                             const std::vector<Eigen::Vector3d>& planes_body, const LocalMap& plane_map,
                             const std::vector<Eigen::Vector3d>& edges_body, const LocalMap& edge_map,
                             const UpdateParams& params, const LocalMap* post_axis_map) {
  const StateCovariance prior_information = prior_covariance.ldlt().solve(StateCovariance::Identity());
  const double inv_var = 1.0 / (params.lidar_noise_m * params.lidar_noise_m);
  UpdateResult result;
  NavState x = prior;
  Normal6 eq;
  StateCovariance information = prior_information;
  Correspondences plane_cache;
  Correspondences edge_cache;
  std::vector<Eigen::Vector3d> planes_world;
  std::vector<Eigen::Vector3d> edges_world;
  NavState searched_at = x;
  int degenerate_directions = 0;
  for (int iteration = 0; iteration < params.max_iterations; ++iteration) {
    // Search again while the pose still moves noticeably since the last search.
    const StateVector moved = boxminus(x, searched_at);
    const bool search = iteration < params.forced_searches || moved.segment<3>(0).norm() > params.research_rotation_rad ||
                        moved.segment<3>(3).norm() > params.research_translation_m;
    if (search) searched_at = x;
    eq = Normal6{};
    accumulate(planes_body, x, planes_world, plane_map, params, plane_correspondence, search, plane_cache, eq);
    if (!edge_map.empty()) {
      std::optional<Eigen::Vector3d> sensor;
      if (params.edge_viewpoint_body) sensor = x.to_world(*params.edge_viewpoint_body);
      const Eigen::Vector3d up = -x.gravity.normalized();
      const bool posts = sensor && params.posts && post_axis_map != nullptr && !post_axis_map->empty();
      std::optional<LocalMap::NeighbourSearch> axes;
      if (posts) axes.emplace(*post_axis_map);
      auto line = [&](LocalMap::NeighbourSearch& ns, const Eigen::Vector3d& q, const CorrespondenceParams& p) {
        if (posts) {
          if (auto post = post_correspondence(*axes, q, up, *sensor, *params.posts)) return post;
        }
        return line_correspondence(ns, q, p, sensor ? &*sensor : nullptr);
      };
      accumulate(edges_body, x, edges_world, edge_map, params, line, search, edge_cache, eq);
    }
    // Degeneracy (Zhang, Kaess, Singh, ICRA 2016): along directions the scene hardly constrains
    // (a tunnel's axis), the LiDAR's few, slightly biased normals would push the pose without
    // information to back it. Remove the LiDAR from those directions; the IMU prior holds them.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(eq.hessian);
    Eigen::Matrix<double, 6, 6> projector = Eigen::Matrix<double, 6, 6>::Zero();
    degenerate_directions = 0;
    for (int i = 0; i < 6; ++i) {
      if (eig.eigenvalues()(i) >= params.degeneracy_eigenvalue || !params.project_degenerate) {
        projector += eig.eigenvectors().col(i) * eig.eigenvectors().col(i).transpose();
      }
      if (eig.eigenvalues()(i) < params.degeneracy_eigenvalue) ++degenerate_directions;
    }
    // MAP step: (P^-1 + H^T W H) delta = -H^T W r - P^-1 (x (-) prior)   (iterated EKF).
    information = prior_information;
    information.topLeftCorner<6, 6>() += inv_var * projector * eq.hessian * projector;
    StateVector rhs = -prior_information * boxminus(x, prior);
    rhs.head<6>() -= inv_var * projector * eq.gradient;
    if (params.vertical_velocity_std > 0.0) add_vertical_velocity_constraint(x, params, information, rhs);
    const StateVector delta = information.ldlt().solve(rhs);
    if (!delta.allFinite()) break;
    x = boxplus(x, delta);
    result.iterations = iteration + 1;
    if (delta.segment<3>(0).norm() < 1e-5 && delta.segment<3>(3).norm() < 1e-4) break;
  }
  result.state = x;
  result.covariance = information.ldlt().solve(StateCovariance::Identity());
  result.covariance = 0.5 * (result.covariance + result.covariance.transpose()).eval();
  result.residuals = eq.count;
  result.rms_residual_m = eq.count > 0 ? std::sqrt(eq.squared_error / eq.count) : 0.0;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> translation(eq.hessian.bottomRightCorner<3, 3>(), Eigen::EigenvaluesOnly);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rotation(eq.hessian.topLeftCorner<3, 3>(), Eigen::EigenvaluesOnly);
  result.min_translation_eigenvalue = translation.eigenvalues()(0);
  result.min_rotation_eigenvalue = rotation.eigenvalues()(0);
  result.degenerate_directions = degenerate_directions;
  return result;
}

}  // namespace liod
