#include "liod/backend/relocalization.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "liod/angles.hpp"

namespace liod {
namespace {

// The keyframe's points for its descriptor: planes and edges (the map's density), in the level
// frame at the sensor.
std::vector<Eigen::Vector3f> level_points(const BackendKeyframe& k, const Eigen::Matrix3d& world_from_body) {
  const Eigen::Matrix3f level = level_from_body(world_from_body).cast<float>();
  std::vector<Eigen::Vector3f> out;
  out.reserve(k.planes.size() + k.edges.size());
  for (const auto& p : k.planes) out.push_back(level * p);
  for (const auto& p : k.edges) out.push_back(level * p);
  return out;
}

double yaw_of(const Eigen::Matrix3d& r) { return std::atan2(r(1, 0), r(0, 0)); }

}  // namespace

Relocalizer::Relocalizer(SavedMap map, std::shared_ptr<KeyframeSpill> clouds, const AlgorithmConfig& config)
    : map_(std::move(map)), clouds_(std::move(clouds)), config_(config) {
  config_.backend.similarity_threshold_m = config.backend.relocalization.similarity_threshold_m;
  config_.backend.loop_max_rms_m = config.backend.relocalization.max_rms_m;
  config_.backend.loop_min_inlier_fraction = config.backend.relocalization.min_inlier_fraction;
}

std::shared_ptr<const BackendKeyframe> Relocalizer::cloud(std::size_t place) {
  // A few sub-maps' worth: an attempt reads the places around one candidate, and the next
  // attempt, a keyframe further on, mostly the same ones.
  const std::size_t keep = 8 * static_cast<std::size_t>(config_.backend.relocalization.submap_keyframes);
  if (const auto it = cache_.find(place); it != cache_.end()) return it->second;
  if (cache_.size() >= keep) cache_.clear();
  auto kf = std::make_shared<const BackendKeyframe>(clouds_->read(map_.ids[place]));
  cache_.emplace(place, kf);
  return kf;
}

void Relocalizer::describe_map() {
  const RelocalizationConfig& c = config_.backend.relocalization;
  const double offsets[] = {0.0, -c.lateral_offset_m, c.lateral_offset_m};
  for (std::size_t k = 0; k < map_.ids.size(); ++k) {
    const std::vector<Eigen::Vector3f> level = level_points(clouds_->read(map_.ids[k]), map_.poses[k].linear());
    for (const double offset : offsets) {
      if (offset != 0.0 && !(c.lateral_offset_m > 0.0)) continue;
      std::vector<Eigen::Vector3f> seen(level);
      for (auto& p : seen) p.y() -= static_cast<float>(offset);
      descriptors_.push_back({make_scan_context(seen, c.scan_context), k, offset});
    }
  }
}

std::optional<Placement> Relocalizer::verify(const BackendKeyframe& keyframe, std::size_t place,
                                             const Eigen::Isometry3d& guess) {
  // The sub-map: the saved keyframes nearest the place (any run, any pass).
  const Eigen::Vector2d centre = map_.poses[place].translation().head<2>();
  std::vector<std::pair<double, std::size_t>> by_distance;
  by_distance.reserve(map_.ids.size());
  for (std::size_t k = 0; k < map_.ids.size(); ++k) {
    by_distance.emplace_back((map_.poses[k].translation().head<2>() - centre).squaredNorm(), k);
  }
  const auto n = std::min<std::size_t>(by_distance.size(), static_cast<std::size_t>(config_.backend.relocalization.submap_keyframes));
  std::partial_sort(by_distance.begin(), by_distance.begin() + static_cast<std::ptrdiff_t>(n), by_distance.end());
  std::vector<PlacedKeyframe> members;
  for (std::size_t i = 0; i < n; ++i) members.push_back({cloud(by_distance[i].second), map_.poses[by_distance[i].second]});
  const SubMap submap = make_submap(members, config_);

  Placement p;
  p.place = place;
  p.check = verify_on_submap(keyframe, guess, submap, to_world(cloud(place)->similarity, map_.poses[place]), config_);
  if (p.check.outcome != LoopOutcome::kAccepted) {
    ++rejected_;
    return std::nullopt;
  }
  p.map_from_body = p.check.registered;
  return p;
}

std::optional<Placement> Relocalizer::place(const BackendKeyframe& keyframe) {
  if (map_.empty()) return std::nullopt;
  if (descriptors_.empty()) describe_map();
  ++attempts_;
  const RelocalizationConfig& c = config_.backend.relocalization;
  const Eigen::Matrix3d& attitude = keyframe.odometry_pose.linear();
  const ScanContext query = make_scan_context(level_points(keyframe, attitude), c.scan_context);

  // 1. Every saved description against the query (the sector keys make each comparison a few
  // thousand operations), the nearest first.
  std::vector<std::pair<ScanContextMatch, const Description*>> matches;
  for (const Description& d : descriptors_) {
    const ScanContextMatch m = match_scan_contexts(query, d.context);
    if (m.distance <= c.max_descriptor_distance) matches.emplace_back(m, &d);
  }
  std::sort(matches.begin(), matches.end(), [](const auto& a, const auto& b) { return a.first.distance < b.first.distance; });

  // 2. Each of the best from the viewpoint described, heading turned by the descriptors' shift:
  // the described level frame is the query's turned by yaw_rad.
  const Eigen::Matrix3d level = level_from_body(attitude);
  std::vector<std::size_t> tried;
  for (const auto& [m, d] : matches) {
    if (tried.size() >= static_cast<std::size_t>(c.verified_candidates)) break;
    if (std::find(tried.begin(), tried.end(), d->place) != tried.end()) continue;  // one sub-map, one test
    tried.push_back(d->place);
    const Eigen::Isometry3d& saved = map_.poses[d->place];
    const Eigen::Matrix3d saved_yaw = Eigen::AngleAxisd(yaw_of(saved.linear()), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
    guess.linear() = saved_yaw * Eigen::AngleAxisd(m.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() * level;
    guess.translation() = saved.translation() + saved_yaw * Eigen::Vector3d(0.0, d->lateral_m, 0.0);
    auto placement = verify(keyframe, d->place, guess);
    if (placement) {
      placement->descriptor_distance = m.distance;
      return placement;
    }
  }
  return std::nullopt;
}

std::optional<Placement> Relocalizer::match(const BackendKeyframe& keyframe, const Eigen::Isometry3d& guess) {
  if (map_.empty()) return std::nullopt;
  std::size_t nearest = 0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < map_.ids.size(); ++k) {
    const double d = (map_.poses[k].translation() - guess.translation()).head<2>().squaredNorm();
    if (d < best) {
      best = d;
      nearest = k;
    }
  }
  // Beyond the registration's reach of every saved keyframe the map has nothing to say here.
  if (std::sqrt(best) > config_.backend.loop_radius_m) return std::nullopt;
  return verify(keyframe, nearest, guess);
}

std::optional<Eigen::Isometry3d> RelocalizationGate::offer(const Placement& placement, const Eigen::Isometry3d& run_from_body) {
  // The full transform: each run's world frame is levelled by its own start, whose accelerometer
  // bias tilts it by a fraction of a degree, so two runs' frames differ in roll and pitch too.
  const Eigen::Isometry3d map_from_run = placement.map_from_body * run_from_body.inverse();
  const Eigen::Vector3d position = run_from_body.translation();
  if (pending_ && (position - pending_position_).norm() >= config_.min_travel_m) {
    // Where the earlier placement and the odometry since put this keyframe, against where the
    // registration puts it (compared at the keyframe: an offset's translation alone would weigh
    // a heading difference by the distance from the run's origin).
    const Eigen::Isometry3d difference = (*pending_ * run_from_body).inverse() * placement.map_from_body;
    const double angle = Eigen::AngleAxisd(difference.linear()).angle();
    if (difference.translation().norm() <= config_.agreement_m && angle <= config_.agreement_deg * kDegToRad) {
      return map_from_run;
    }
  }
  // Too near the last one to be independent (keep the older), or it disagrees (start again).
  if (!pending_ || (position - pending_position_).norm() >= config_.min_travel_m) {
    pending_ = map_from_run;
    pending_position_ = position;
  }
  return std::nullopt;
}

}  // namespace liod

