#pragma once
// liod's backend (the seed paper's module 3; docs/backend.md): keyframes from the front end go into a pose
// graph; each new keyframe is checked for a loop against older ones (loop_closure.hpp) and a
// verified loop triggers a full pose-graph solve. Between loops the graph only chains the
// odometry (no solve), so a long drive stays cheap. The result is a correction T_world_odom
// that the pose output applies to the odometry's poses; the odometry itself keeps its own frame.
// Pure: no threads, no I/O (persistence is map_store.hpp); the daemon runs it on its own
// low-priority thread.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "liod/backend/keyframe_store.hpp"
#include "liod/backend/loop_closure.hpp"
#include "liod/backend/pose_graph.hpp"
#include "liod/backend/relocalization.hpp"
#include "liod/algorithm_config.hpp"
#include "liod/imu_preintegration.hpp"
#include "liod/keyframe.hpp"

namespace liod {

struct BackendStats {
  std::size_t keyframes = 0;
  std::size_t loops_accepted = 0;
  std::size_t loops_rejected = 0;  // candidates verified and rejected, any reason
  std::array<std::size_t, 6> outcomes{};  // per LoopOutcome
  std::vector<double> solve_ms;    // one per full solve
  std::vector<double> check_ms;    // one per candidate verified
  std::size_t relocalization_attempts = 0;  // keyframes looked up in the saved map
  std::size_t placements = 0;      // ... placed there (verified; the gate accepts the second that agrees)
  std::size_t map_matches = 0;     // localise mode: keyframes registered on the map once placed
  double localized_time = 0.0;     // the keyframe time at which the run was placed in the saved map
  std::uint64_t localized_keyframe = 0;  // ... and that keyframe's id
};

class Backend {
 public:
  /// `spill`: where keyframe clouds go beyond backend.memory_keyframes (nullptr: all stay in
  /// memory; the daemon passes a KeyframeDirectory, map_store.hpp). `first_keyframe_id`: the
  /// backend's id of a keyframe is this plus the front end's (which counts from 0 in every
  /// process), so that a run persisting into a state directory that earlier runs filled keeps
  /// their keyframes (StateWriter::first_keyframe_id()).
  explicit Backend(const AlgorithmConfig& config, std::shared_ptr<KeyframeSpill> spill = nullptr,
                   std::uint64_t first_keyframe_id = 0);

  /// A saved map to continue (backend.mode map) or to track in (localise): until a keyframe is
  /// placed in it (relocalization.hpp) the run is not localised; then its graph moves into the
  /// map's frame. An empty map changes nothing (the run's own frame is the map's).
  void use_saved_map(std::unique_ptr<Relocalizer> relocalizer);
  /// Whether the correction places the run in the map: always without a saved map.
  bool localized() const { return localized_; }
  /// Counts the changes of correction() (loops, the placement in a saved map, map matches).
  std::uint64_t correction_version() const { return correction_version_; }

  /// Adds a keyframe (its points are in the odometry's world frame, as the front end keeps
  /// them); returns true when it closed a loop (and the graph was re-optimised).
  bool add_keyframe(const Keyframe& keyframe);

  /// T_world_odom: maps the odometry's poses into the optimised world frame, from the newest
  /// keyframe (optimised pose * odometry pose^-1). Identity before the first loop.
  Eigen::Isometry3d correction() const;
  /// Optimised T_world_body of every keyframe, in the order added.
  std::vector<Eigen::Isometry3d> optimized_keyframe_poses() const { return graph_.poses(); }
  /// The odometry's poses corrected: the keyframe corrections interpolated in time (slerp /
  /// lerp) between the keyframes around each pose, held constant outside them.
  std::vector<NavState> corrected_trajectory(const std::vector<NavState>& odometry_poses) const;

  /// Every keyframe's points (planes and edges) at the optimised poses, voxel-downsampled.
  /// Spilled clouds are read one at a time, so the memory is the map's, not the drive's.
  std::vector<Eigen::Vector3d> global_map(double voxel_m) const;

  const BackendStats& stats() const { return stats_; }
  /// Every verified candidate, in order (for logs and tests).
  const std::vector<LoopCheck>& loop_checks() const { return checks_; }
  const KeyframeStore& keyframes() const { return keyframes_; }
  const PoseGraph& graph() const { return graph_; }

 private:
  void add_imu_factor(std::size_t previous, const Keyframe& keyframe);
  Matrix6d odometry_information(const Keyframe& keyframe) const;
  bool search_loop(std::size_t current);
  bool close_loop(const LoopCheck& check);
  void relocalize(std::size_t node);
  void match_map(std::size_t node);
  void move_graph(const Eigen::Isometry3d& delta);
  Eigen::Vector3d map_up_in_body(const Eigen::Isometry3d& odometry_pose) const;

  AlgorithmConfig config_;
  PoseGraph graph_;
  KeyframeStore keyframes_;
  std::vector<LoopCheck> checks_;
  BackendStats stats_;
  int cooldown_ = 0;
  std::uint64_t first_keyframe_id_ = 0;
  std::unique_ptr<Relocalizer> relocalizer_;
  std::optional<RelocalizationGate> gate_;
  bool localized_ = true;
  double next_attempt_time_ = -std::numeric_limits<double>::infinity();
  std::uint64_t correction_version_ = 0;
  Eigen::Matrix3d map_from_run_rotation_ = Eigen::Matrix3d::Identity();  // the moves' rotation so far
  NavState last_state_;                                          // the newest keyframe's, as the front end sent it
  PoseCovariance last_pose_covariance_ = PoseCovariance::Zero();
};

}  // namespace liod
