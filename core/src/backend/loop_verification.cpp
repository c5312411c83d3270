// Loop verification: the candidate's sub-map, the scan registered on it, and the checks that
// accept the registration as a loop (loop_closure.hpp, steps 3 and 4).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "liod/angles.hpp"
#include "liod/backend/loop_closure.hpp"
#include "liod/iterated_update.hpp"
#include "liod/local_map.hpp"
#include "liod/map_correspondence.hpp"
#include "liod/so3.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {

std::vector<Eigen::Vector3d> to_world(const std::vector<Eigen::Vector3f>& body, const Eigen::Isometry3d& pose) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(body.size());
  for (const auto& p : body) out.push_back(pose * p.cast<double>());
  return out;
}

namespace {

std::vector<Eigen::Vector3d> to_double(const std::vector<Eigen::Vector3f>& in) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(in.size());
  for (const auto& p : in) out.push_back(p.cast<double>());
  return out;
}

Eigen::Vector3d up_in_body(const Eigen::Isometry3d& pose) { return pose.linear().transpose() * Eigen::Vector3d::UnitZ(); }

// The candidate's sub-map in the graph's world frame: the candidate's neighbours only, never the
// recent keyframes of the current pass.
SubMap candidate_submap(KeyframeStore& keyframes, const std::vector<Eigen::Isometry3d>& poses, std::size_t current,
                        std::size_t candidate, const AlgorithmConfig& config) {
  const std::size_t n = static_cast<std::size_t>(config.backend.submap_keyframes);
  const std::size_t first = candidate > n ? candidate - n : 0;
  const std::size_t last = std::min({candidate + n, current - 1, keyframes.size() - 1});
  std::vector<PlacedKeyframe> members;
  for (std::size_t k = first; k <= last; ++k) {
    if (keyframes.time(current) - keyframes.time(k) < config.backend.loop_time_gap_s) continue;
    members.push_back({keyframes.get(k), poses[k]});
  }
  return make_submap(members, config);
}

// Scan-to-map registration: the front end's iterated update with a weak prior (a LiDAR-only
// Gauss-Newton); the prior is re-centred on each round's result so that it only regularises.
// Coarse to fine gate: the first rounds search neighbours as far as the map's voxel allows (the
// coarse alignment leaves up to ~0.5 m), the last ones at the front end's gate.
void register_on_submap(const std::vector<Eigen::Vector3d>& planes, const std::vector<Eigen::Vector3d>& edges,
                        const Eigen::Isometry3d& initial, const SubMap& submap, const OdometryConfig& odometry,
                        UpdateParams& params, LoopCheck& check) {
  StateCovariance weak = StateCovariance::Identity();
  weak.diagonal().segment<3>(0).setConstant(std::pow(5.0 * kDegToRad, 2));
  weak.diagonal().segment<3>(3).setConstant(2.0 * 2.0);
  NavState x;
  x.rotation = initial.linear();
  x.position = initial.translation();
  UpdateResult result;
  constexpr int kRounds = 5;
  const double fine_gate = odometry.max_correspondence_m;
  const double coarse_gate = std::max(fine_gate, odometry.map_voxel_m);
  for (int round = 0; round < kRounds; ++round) {
    params.correspondence.max_distance_m = round < 2 ? coarse_gate : fine_gate;
    result = iterated_update(x, weak, planes, submap.planes, edges, submap.edges, params);
    const StateVector moved = boxminus(result.state, x);
    x = result.state;
    if (round >= 2 && moved.segment<3>(0).norm() < 0.05 * kDegToRad && moved.segment<3>(3).norm() < 0.01) {
      check.converged = true;
      break;
    }
  }
  Eigen::Isometry3d registered = Eigen::Isometry3d::Identity();
  registered.linear() = so3::normalize(x.rotation);
  registered.translation() = x.position;
  check.registered = registered;
  check.degenerate_directions = result.degenerate_directions;
}

// Fit: rms over the points that found a plane; a point is an inlier when its residual is within
// inlier_m (the fraction counts every query, matched or not).
void measure_fit(const std::vector<Eigen::Vector3d>& planes, const LocalMap& plane_map,
                 const CorrespondenceParams& correspondence, double inlier_m, LoopCheck& check) {
  int inliers = 0;
  double squared = 0.0;
  int matched = 0;
  LocalMap::NeighbourSearch plane_search(plane_map);
  for (const auto& p : planes) {
    const Eigen::Vector3d q = check.registered * p;
    const auto plane = plane_correspondence(plane_search, q, correspondence);
    if (!plane) continue;
    const double r = plane->evaluate(q);
    squared += r * r;
    ++matched;
    if (std::abs(r) <= inlier_m) ++inliers;
  }
  check.inlier_fraction = planes.empty() ? 0.0 : static_cast<double>(inliers) / static_cast<double>(planes.size());
  check.rms_m = matched > 0 ? std::sqrt(squared / matched) : 0.0;
}

}  // namespace

SubMap make_submap(const std::vector<PlacedKeyframe>& members, const AlgorithmConfig& config) {
  const LocalMap empty(config.odometry.map_voxel_m, config.odometry.map_points_per_voxel,
                       config.odometry.map_min_point_spacing_m);
  SubMap submap{{}, empty, empty};
  for (const auto& [kf, pose] : members) {
    const auto sim = to_world(kf->similarity, pose);
    submap.similarity.insert(submap.similarity.end(), sim.begin(), sim.end());
    submap.planes.add(to_world(kf->planes, pose), kf->id);
    submap.edges.add(to_world(kf->edges, pose), kf->id);
  }
  return submap;
}

LoopCheck verify_on_submap(const BackendKeyframe& current, const Eigen::Isometry3d& guess, const SubMap& submap,
                           const std::vector<Eigen::Vector3d>& candidate_world, const AlgorithmConfig& config) {
  const auto start = std::chrono::steady_clock::now();
  const BackendConfig& b = config.backend;
  LoopCheck check;
  auto done = [&](LoopOutcome outcome) {
    check.outcome = outcome;
    check.check_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return check;
  };

  // 1. Similarity: the scan against the sub-map after a coarse alignment search.
  Eigen::Isometry3d initial = guess;
  if (b.similarity_check) {
    const auto similarity = similarity_search(to_double(current.similarity), guess, submap.similarity, candidate_world, b);
    check.similarity_m = similarity.distance_m;
    check.similarity_forward_m = similarity.forward_m;
    check.similarity_backward_m = similarity.backward_m;
    if (similarity.distance_m > b.similarity_threshold_m) return done(LoopOutcome::kDissimilar);
    initial = similarity.aligned;
  }

  // 2. Registration on the sub-map, and its fit.
  UpdateParams params;
  params.max_iterations = 10;
  params.lidar_noise_m = config.odometry.lidar_noise_m;
  params.correspondence.max_distance_m = config.odometry.max_correspondence_m;
  params.degeneracy_eigenvalue = config.odometry.degeneracy_eigenvalue;
  const std::vector<Eigen::Vector3d> planes = voxel_downsample(to_double(current.planes), config.odometry.plane_voxel_m);
  const std::vector<Eigen::Vector3d> edges = voxel_downsample(to_double(current.edges), config.odometry.edge_voxel_m);
  register_on_submap(planes, edges, initial, submap, config.odometry, params, check);
  measure_fit(planes, submap.planes, params.correspondence, 2.0 * b.loop_max_rms_m, check);
  if (!check.converged || check.degenerate_directions > 0 || check.rms_m > b.loop_max_rms_m ||
      check.inlier_fraction < b.loop_min_inlier_fraction) {
    return done(LoopOutcome::kRegistrationFailed);
  }

  // 3. Vertical check against the guess (not the coarse alignment, which searched z).
  check.dz_m = check.registered.translation().z() - guess.translation().z();
  const double c = std::clamp(up_in_body(check.registered).dot(up_in_body(guess)), -1.0, 1.0);
  check.tilt_deg = std::acos(c) / kDegToRad;
  if (std::abs(check.dz_m) > b.max_vertical_m || check.tilt_deg > b.max_tilt_deg) {
    return done(LoopOutcome::kVerticalDisagreement);
  }
  return done(LoopOutcome::kAccepted);
}

LoopCheck check_loop(KeyframeStore& keyframes, const std::vector<Eigen::Isometry3d>& poses, std::size_t current,
                     std::size_t candidate, const AlgorithmConfig& config) {
  const auto candidate_kf = keyframes.get(candidate);
  const SubMap submap = candidate_submap(keyframes, poses, current, candidate, config);
  LoopCheck check = verify_on_submap(*keyframes.get(current), poses[current], submap,
                                     to_world(candidate_kf->similarity, poses[candidate]), config);
  check.current = current;
  check.candidate = candidate;
  if (check.outcome == LoopOutcome::kAccepted) check.measured = poses[candidate].inverse() * check.registered;
  return check;
}

LoopCheck check_loop(const std::vector<BackendKeyframe>& keyframes, const std::vector<Eigen::Isometry3d>& poses,
                     std::size_t current, std::size_t candidate, const AlgorithmConfig& config) {
  KeyframeStore store(0, nullptr);
  for (const auto& k : keyframes) store.add(k);
  return check_loop(store, poses, current, candidate, config);
}

}  // namespace liod
