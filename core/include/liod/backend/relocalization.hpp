#pragma once
// Relocalisation in a saved map: where is the vehicle in a map that an earlier run made, starting
// from nothing (an unknown position and heading). Two steps per attempt:
//  1. place recognition: the keyframe's Scan Context (scan_context.hpp) against every saved
//     keyframe's (each also described from a lane to its left and right), giving a saved place,
//     a viewpoint near it and the relative heading;
//  2. confirmation: the loop closure's own test (loop_closure.hpp: similarity, registration on
//     the place's sub-map, fit limits, vertical check) from that place and heading.
// A confirmed placement is still one registration, which a repetitive street can fit wrongly; the
// backend accepts it only when a second one, found as independently from a keyframe further on,
// agrees (RelocalizationGate). Pure: the saved clouds are read through a KeyframeSpill.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "liod/algorithm_config.hpp"
#include "liod/backend/keyframe_store.hpp"
#include "liod/backend/loop_closure.hpp"
#include "liod/backend/scan_context.hpp"

namespace liod {

/// The saved keyframes of a map, their poses in the map frame.
struct SavedMap {
  std::vector<std::uint64_t> ids;
  std::vector<Eigen::Isometry3d> poses;
  bool empty() const { return ids.empty(); }
};

struct Placement {
  Eigen::Isometry3d map_from_body = Eigen::Isometry3d::Identity();  // the registered pose
  std::size_t place = 0;           // the saved keyframe it was placed at (index into SavedMap)
  double descriptor_distance = 1.0;
  LoopCheck check;
};

class Relocalizer {
 public:
  /// `clouds`: where the saved keyframes' clouds are read from (the state directory).
  Relocalizer(SavedMap map, std::shared_ptr<KeyframeSpill> clouds, const AlgorithmConfig& config);

  /// Step 1 and 2 for a keyframe whose odometry pose gives its tilt. Reads every saved keyframe
  /// once, on the first call, to describe it. Throws what the spill throws.
  std::optional<Placement> place(const BackendKeyframe& keyframe);
  /// Step 2 alone near a known map pose `guess` (T_map_body): tracking in the map once placed.
  std::optional<Placement> match(const BackendKeyframe& keyframe, const Eigen::Isometry3d& guess);

  std::size_t size() const { return map_.ids.size(); }
  const SavedMap& map() const { return map_; }
  /// Attempts made and verified candidates rejected, for the log.
  std::size_t attempts() const { return attempts_; }
  std::size_t rejected() const { return rejected_; }

 private:
  void describe_map();
  std::shared_ptr<const BackendKeyframe> cloud(std::size_t place);
  std::optional<Placement> verify(const BackendKeyframe& keyframe, std::size_t place, const Eigen::Isometry3d& guess);

  SavedMap map_;
  std::shared_ptr<KeyframeSpill> clouds_;
  AlgorithmConfig config_;
  struct Description {
    ScanContext context;
    std::size_t place = 0;
    double lateral_m = 0.0;  // the viewpoint described: this far along the place's level y axis
  };
  std::vector<Description> descriptors_;
  std::unordered_map<std::size_t, std::shared_ptr<const BackendKeyframe>> cache_;
  std::size_t attempts_ = 0;
  std::size_t rejected_ = 0;
};

/// Accepts a placement once a later one agrees with it (RelocalizationConfig: after min_travel_m,
/// within agreement_m and agreement_deg): the offset T_map_run between the run's world frame and
/// the map's, from the placement of a keyframe whose run-frame pose is `run_from_body`.
class RelocalizationGate {
 public:
  explicit RelocalizationGate(const RelocalizationConfig& config) : config_(config) {}
  std::optional<Eigen::Isometry3d> offer(const Placement& placement, const Eigen::Isometry3d& run_from_body);

 private:
  RelocalizationConfig config_;
  std::optional<Eigen::Isometry3d> pending_;  // T_map_run of the last placement
  Eigen::Vector3d pending_position_ = Eigen::Vector3d::Zero();  // its keyframe, run frame
};

}  // namespace liod
