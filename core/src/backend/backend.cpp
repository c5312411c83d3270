#include "liod/backend/backend.hpp"

#include <algorithm>
#include <cmath>

#include "liod/angles.hpp"
#include "liod/backend/odometry_factor.hpp"
#include "liod/unit_configs.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {
namespace {

constexpr double kOdometryFloor_m = 1e-4;
constexpr double kOdometryFloor_deg = 1e-3;

Eigen::Isometry3d isometry(const NavState& s) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = s.rotation;
  t.translation() = s.position;
  return t;
}

std::vector<Eigen::Vector3f> to_body(const std::vector<Eigen::Vector3d>& world, const Eigen::Isometry3d& world_from_body,
                                     double voxel_m) {
  const Eigen::Isometry3d body_from_world = world_from_body.inverse();
  std::vector<Eigen::Vector3d> body;
  body.reserve(world.size());
  for (const auto& p : world) body.push_back(body_from_world * p);
  if (voxel_m > 0.0) body = voxel_downsample(body, voxel_m);
  std::vector<Eigen::Vector3f> out;
  out.reserve(body.size());
  for (const auto& p : body) out.push_back(p.cast<float>());
  return out;
}

// a * (1 - s) + b * s on SE(3) as slerp / lerp: enough for corrections that differ little
// between neighbouring keyframes.
Eigen::Isometry3d interpolate(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double s) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond qa(a.linear());
  const Eigen::Quaterniond qb(b.linear());
  out.linear() = qa.slerp(s, qb).normalized().toRotationMatrix();
  out.translation() = (1.0 - s) * a.translation() + s * b.translation();
  return out;
}

// The graph's world frame differs from the odometry's by the correction at the node: a vector of
// the odometry's world (velocity, gravity) turns by this into the graph's.
Eigen::Matrix3d graph_from_odometry(const NavState& odometry, const Eigen::Isometry3d& graph_pose) {
  return graph_pose.linear() * odometry.rotation.transpose();
}

NodeMotion motion_in_graph(const NavState& odometry, const Eigen::Isometry3d& graph_pose) {
  return {graph_from_odometry(odometry, graph_pose) * odometry.velocity, odometry.gyro_bias, odometry.accel_bias};
}

// Whether the intervals measure exactly [from, to]: the front end's stretch since the previous
// keyframe, unbroken (keyframe.hpp). A keyframe that came after a reset of the front end, or a
// backend that missed one, has intervals from another start.
bool covers(const std::vector<ImuInterval>& intervals, double from, double to) {
  constexpr double kTolerance_s = 1e-6;
  if (intervals.empty() || std::abs(intervals.front().start_time - from) > kTolerance_s) return false;
  double t = from;
  for (const auto& iv : intervals) {
    if (std::abs(iv.start_time - t) > kTolerance_s || !(iv.dt >= 0.0)) return false;
    t = iv.start_time + iv.dt;
  }
  return std::abs(t - to) <= kTolerance_s;
}

}  // namespace

Backend::Backend(const AlgorithmConfig& config, std::shared_ptr<KeyframeSpill> spill, std::uint64_t first_keyframe_id)
    : config_(config),
      keyframes_(static_cast<std::size_t>(config.backend.memory_keyframes), std::move(spill)),
      first_keyframe_id_(first_keyframe_id) {}

bool Backend::add_keyframe(const Keyframe& keyframe) {
  const BackendConfig& b = config_.backend;
  BackendKeyframe k;
  k.id = first_keyframe_id_ + keyframe.id;
  k.time = keyframe.state.time;
  k.odometry_pose = isometry(keyframe.state);
  k.planes = to_body(keyframe.planes_world, k.odometry_pose, b.keyframe_voxel_m);
  k.edges = to_body(keyframe.edges_world, k.odometry_pose, b.keyframe_voxel_m);
  k.similarity = to_body(keyframe.similarity_cloud_world, k.odometry_pose, 0.0);

  std::size_t node = 0;
  if (keyframes_.empty()) {
    node = graph_.add_node(k.odometry_pose);  // held fixed: the world frame is the odometry's
  } else {
    // Between loops the graph only chains the odometry: the new node continues from its
    // predecessor's optimised pose by the odometry increment (no solve).
    const std::size_t previous = keyframes_.size() - 1;
    const Eigen::Isometry3d increment = keyframes_.odometry_pose(previous).inverse() * k.odometry_pose;
    node = graph_.add_node(graph_.pose(previous) * increment);
    PoseGraphFactor f;
    f.from = previous;
    f.to = node;
    f.measured = increment;
    f.information = odometry_information(keyframe);
    graph_.add_factor(f);
  }
  last_state_ = keyframe.state;
  last_pose_covariance_ = keyframe.pose_covariance;
  const Eigen::Vector3d up = map_up_in_body(k.odometry_pose);
  graph_.set_motion(node, motion_in_graph(keyframe.state, graph_.pose(node)));
  if (b.imu_factors && node > 0) add_imu_factor(node - 1, keyframe);
  keyframes_.add(std::move(k));
  if (b.tilt_sigma_deg > 0.0) graph_.set_tilt(node, up, b.tilt_sigma_deg * kDegToRad);
  ++stats_.keyframes;

  if (relocalizer_ && (!localized_ || b.mode == BackendMode::kLocalize) && keyframes_.time(node) >= next_attempt_time_) {
    next_attempt_time_ = keyframes_.time(node) + (localized_ ? b.relocalization.match_interval_s : b.relocalization.interval_s);
    if (localized_) match_map(node);
    else relocalize(node);
  }
  // Localising, the saved map is the reference: the run's own loops would only repeat it.
  if (b.mode == BackendMode::kLocalize) return false;
  if (cooldown_ > 0) {
    --cooldown_;
    return false;
  }
  const bool closed = search_loop(node);
  correction_version_ += closed ? 1 : 0;
  return closed;
}

// The previous keyframe's and this one's covariance carried into their relative pose, or the fixed
// sigmas where a covariance is unknown.
Matrix6d Backend::odometry_information(const Keyframe& keyframe) const {
  const BackendConfig& b = config_.backend;
  if (b.odometry_weights == OdometryWeights::kCovariance && !last_pose_covariance_.isZero() &&
      !keyframe.pose_covariance.isZero()) {
    const Matrix6d covariance = relative_pose_covariance(last_state_, last_pose_covariance_, keyframe.state, keyframe.pose_covariance);
    return relative_pose_information(covariance, kOdometryFloor_m, kOdometryFloor_deg * kDegToRad);
  }
  return relative_pose_information(b.odometry_translation_sigma_m, b.odometry_rotation_sigma_deg * kDegToRad);
}

// The IMU between the previous keyframe and this one, preintegrated at the previous node's biases.
void Backend::add_imu_factor(std::size_t previous, const Keyframe& keyframe) {
  const std::vector<ImuInterval>& intervals = keyframe.imu_since_previous;
  if (!covers(intervals, keyframes_.time(previous), keyframe.state.time)) return;
  const NodeMotion& start = graph_.motion(previous);
  auto preintegration = std::make_shared<ImuPreintegration>(start.gyro_bias, start.accel_bias, imu_noise(config_.imu));
  for (const auto& iv : intervals) preintegration->integrate(iv.gyro, iv.accel, iv.dt);
  const double dt = preintegration->duration();
  ImuGraphFactor f;
  f.from = previous;
  f.to = previous + 1;
  f.gravity = graph_from_odometry(keyframe.state, graph_.pose(f.to)) * keyframe.state.gravity;
  f.gyro_bias_walk_sigma = config_.imu.gyro_bias_random_walk * std::sqrt(dt);
  f.accel_bias_walk_sigma = config_.imu.accel_bias_random_walk * std::sqrt(dt);
  f.preintegration = std::move(preintegration);
  graph_.add_imu_factor(std::move(f));
}

void Backend::use_saved_map(std::unique_ptr<Relocalizer> relocalizer) {
  const bool has_map = relocalizer && relocalizer->size() > 0;
  // Mapping, a run without a map to join starts the map; localising, it has nothing to track in.
  if (!has_map && config_.backend.mode == BackendMode::kMap) return;
  if (has_map) relocalizer_ = std::move(relocalizer);
  gate_.emplace(config_.backend.relocalization);
  localized_ = false;
}

void Backend::relocalize(std::size_t node) {
  ++stats_.relocalization_attempts;
  const auto current = keyframes_.get(node);
  const auto placement = relocalizer_->place(*current);
  if (!placement) return;
  ++stats_.placements;
  const auto map_from_run = gate_->offer(*placement, graph_.pose(node));
  if (!map_from_run) return;
  move_graph(*map_from_run);
  localized_ = true;
  stats_.localized_time = keyframes_.time(node);
  stats_.localized_keyframe = keyframes_.id(node);
}

void Backend::match_map(std::size_t node) {
  const auto current = keyframes_.get(node);
  const auto placement = relocalizer_->match(*current, graph_.pose(node));
  if (!placement) return;
  ++stats_.map_matches;
  move_graph(placement->map_from_body * graph_.pose(node).inverse());
}

// Moves the whole graph rigidly (its factors are relative, so none changes): the run's frame
// becomes the map's. The tilt factors follow: the map's up, seen from each body, is the run's up
// turned by the frames' relative roll and pitch.
void Backend::move_graph(const Eigen::Isometry3d& delta) {
  map_from_run_rotation_ = delta.linear() * map_from_run_rotation_;
  const double sigma = config_.backend.tilt_sigma_deg * kDegToRad;
  graph_.transform(delta);
  for (std::size_t k = 0; k < graph_.size(); ++k) {
    if (sigma > 0.0) graph_.set_tilt(k, map_up_in_body(keyframes_.odometry_pose(k)), sigma);
  }
  ++correction_version_;
}

Eigen::Vector3d Backend::map_up_in_body(const Eigen::Isometry3d& odometry_pose) const {
  return (map_from_run_rotation_ * odometry_pose.linear()).transpose() * Eigen::Vector3d::UnitZ();
}

bool Backend::search_loop(std::size_t current) {
  const BackendConfig& b = config_.backend;
  const auto candidates =
      loop_candidates(graph_.poses(), keyframes_.times(), current, b, static_cast<std::size_t>(b.loop_candidates));
  for (const std::size_t candidate : candidates) {
    LoopCheck check = check_loop(keyframes_, graph_.poses(), current, candidate, config_);
    stats_.check_ms.push_back(check.check_ms);
    bool closed = false;
    if (check.outcome == LoopOutcome::kAccepted) {
      closed = close_loop(check);
      if (!closed) check.outcome = LoopOutcome::kInconsistent;
    }
    ++stats_.outcomes[static_cast<std::size_t>(check.outcome)];
    checks_.push_back(check);
    if (closed) {
      ++stats_.loops_accepted;
      cooldown_ = b.loop_cooldown_keyframes;
      return true;
    }
    ++stats_.loops_rejected;
  }
  return false;
}

bool Backend::close_loop(const LoopCheck& check) {
  const BackendConfig& b = config_.backend;
  const std::vector<Eigen::Isometry3d> before = graph_.poses();
  const double scale = b.robust_loss_scale;
  auto outliers = [&]() {
    std::size_t n = 0;
    for (const auto& f : graph_.factors()) n += f.loop && graph_.whitened_error(f) > scale ? 1 : 0;
    return n;
  };
  const std::size_t outliers_before = scale > 0.0 ? outliers() : 0;

  // The solve's window: the keyframes since the candidate, at most solve_window_keyframes of
  // them (0: the whole graph). Older nodes are held; the loops and odometry factors that reach
  // into the window from them anchor it. This bounds the cost of a solve on a long drive (a full
  // solve grew to 4 s at 13 000 keyframes); the price is that a loop with an old candidate bends
  // only the window, not the whole stretch since the candidate.
  const std::size_t j = check.candidate;
  const std::size_t c = check.current;
  const std::size_t window = static_cast<std::size_t>(b.solve_window_keyframes);
  const std::size_t first_free = window == 0 ? 0 : std::max(j, c + 1 > window ? c + 1 - window : 0);

  // Initial guess with the new loop closed: its error (registered vs graph pose of the current
  // keyframe) spread along the free keyframes since the candidate. Starting the solve from there
  // keeps a redescending (Cauchy) kernel from treating a large but true drift as an outlier.
  const std::size_t anchor = first_free > j ? first_free - 1 : j;
  const Eigen::Isometry3d delta = check.registered * graph_.pose(c).inverse();
  for (std::size_t k = anchor + 1; k <= c; ++k) {
    const double s = static_cast<double>(k - anchor) / static_cast<double>(c - anchor);
    graph_.set_pose(k, interpolate(Eigen::Isometry3d::Identity(), delta, s) * graph_.pose(k));
  }
  PoseGraphFactor f;
  f.from = j;
  f.to = c;
  f.measured = check.measured;
  f.information = relative_pose_information(b.loop_translation_sigma_m, b.loop_rotation_sigma_deg * kDegToRad);
  f.loop = true;
  graph_.add_factor(f);
  const SolveReport report =
      graph_.optimize(scale > 0.0 ? RobustLoss::kCauchy : RobustLoss::kNone, scale, b.max_solver_iterations, first_free);
  stats_.solve_ms.push_back(report.solve_ms);

  // Consistency: a loop the solution leaves beyond the kernel scale, or one that turns earlier
  // loops into outliers, disagrees with the rest of the graph: undo it.
  if (scale > 0.0 && (graph_.whitened_error(graph_.factors().back()) > scale || outliers() > outliers_before)) {
    graph_.pop_factor();
    for (std::size_t k = 0; k < before.size(); ++k) graph_.set_pose(k, before[k]);
    return false;
  }
  return true;
}

Eigen::Isometry3d Backend::correction() const {
  if (keyframes_.empty()) return Eigen::Isometry3d::Identity();
  return graph_.poses().back() * keyframes_.odometry_pose(keyframes_.size() - 1).inverse();
}

std::vector<NavState> Backend::corrected_trajectory(const std::vector<NavState>& odometry_poses) const {
  std::vector<NavState> out = odometry_poses;
  if (keyframes_.empty()) return out;
  std::vector<Eigen::Isometry3d> corrections(keyframes_.size());
  for (std::size_t k = 0; k < keyframes_.size(); ++k) {
    corrections[k] = graph_.pose(k) * keyframes_.odometry_pose(k).inverse();
  }
  const std::vector<double>& times = keyframes_.times();
  for (auto& s : out) {
    const auto it = std::upper_bound(times.begin(), times.end(), s.time);
    Eigen::Isometry3d c;
    if (it == times.begin()) {
      c = corrections.front();
    } else if (it == times.end()) {
      c = corrections.back();
    } else {
      const auto k1 = static_cast<std::size_t>(it - times.begin());
      const std::size_t k0 = k1 - 1;
      const double span = times[k1] - times[k0];
      const double a = span > 0.0 ? (s.time - times[k0]) / span : 0.0;
      c = interpolate(corrections[k0], corrections[k1], a);
    }
    s.rotation = c.linear() * s.rotation;
    s.position = c * s.position;
    s.velocity = c.linear() * s.velocity;
  }
  return out;
}

std::vector<Eigen::Vector3d> Backend::global_map(double voxel_m) const {
  // voxel_downsample keeps the first point of each voxel, so downsampling the running result
  // whenever the buffer grows gives the same map as one pass over all points, in bounded memory.
  constexpr std::size_t kFlushPoints = 2'000'000;
  std::vector<Eigen::Vector3d> points;
  std::size_t kept = 0;
  for (std::size_t k = 0; k < keyframes_.size(); ++k) {
    const Eigen::Isometry3d& pose = graph_.pose(k);
    const auto kf = keyframes_.peek(k);
    for (const auto& p : kf->planes) points.push_back(pose * p.cast<double>());
    for (const auto& p : kf->edges) points.push_back(pose * p.cast<double>());
    if (points.size() - kept > kFlushPoints) {
      points = voxel_downsample(points, voxel_m);
      kept = points.size();
    }
  }
  return voxel_downsample(points, voxel_m);
}

}  // namespace liod
