#pragma once
// Loop-closure detection and verification (the seed paper, "Loop closure"), pure functions:
//  1. candidates: past keyframes older than a time gap within a radius of the current keyframe,
//     measured in the x-y plane (z drifts most) or in 3D (ablation);
//  2. similarity: a Hausdorff test between the current keyframe's cloud and the candidate's
//     sub-map (candidate +- N keyframes) after a coarse alignment search around the odometry's
//     guess; the partial (quantile) Hausdorff distance of Huttenlocher et al. (PAMI 1993) is used
//     because a scan and a sub-map never see exactly the same surfaces (occlusion, viewpoint),
//     which saturates the max of the classic distance; quantile 1 gives the classic one;
//  3. scan-to-map registration with the front end's iterated update under a weak prior, accepted
//     if it converges with a small residual and enough inliers;
//  4. a vertical check: the registered pose must agree with the graph's height and tilt (gravity
//     makes roll/pitch observable), so another level of a ramp or a parking deck cannot close.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include <memory>
#include <utility>

#include "liod/backend/keyframe_store.hpp"
#include "liod/algorithm_config.hpp"
#include "liod/local_map.hpp"

namespace liod {

/// Node indices of the loop candidates of node `current`, nearest first (at most `limit`).
std::vector<std::size_t> loop_candidates(const std::vector<Eigen::Isometry3d>& poses, const std::vector<double>& times,
                                         std::size_t current, const BackendConfig& config, std::size_t limit);

/// The q-quantile of the nearest-neighbour distances from a to b (q = 1: the directed Hausdorff
/// distance h(a, b)), distances saturated at cap.
double partial_directed_hausdorff(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
                                  double quantile, double cap);
/// max(h_q(a, b), h_q(b, a)).
double partial_hausdorff(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, double quantile,
                         double cap);

struct SimilarityResult {
  double distance_m = 0.0;  // partial Hausdorff distance at the best alignment: max of the two below
  double forward_m = 0.0;   // h_q(scan, sub-map)
  double backward_m = 0.0;  // h_q(candidate keyframe, scan)
  Eigen::Isometry3d aligned = Eigen::Isometry3d::Identity();  // T_world_body of the best alignment
};

/// Searches x, y (+- config.similarity_search_m), yaw (+- similarity_search_yaw_deg) and a small
/// z offset (+- max_vertical_m / 2) around `guess` for the alignment of `cloud_body` that best
/// matches `submap_world`, then scores it with the bidirectional partial Hausdorff distance:
/// scan -> sub-map, and candidate keyframe -> scan (the sub-map covers far more than one scan
/// sees, so the reverse direction uses the candidate's own cloud within the scan's reach).
/// Only structure takes part (points > 0.4 m above the lowest point of their 2 m x-y cell): the
/// ground of one place matches the ground of any other.
SimilarityResult similarity_search(const std::vector<Eigen::Vector3d>& cloud_body, const Eigen::Isometry3d& guess,
                                   const std::vector<Eigen::Vector3d>& submap_world,
                                   const std::vector<Eigen::Vector3d>& candidate_world, const BackendConfig& config);

enum class LoopOutcome {
  kAccepted,
  kNoCandidate,
  kDissimilar,           // the Hausdorff similarity test failed
  kRegistrationFailed,   // no convergence, large residual, few inliers or degenerate
  kVerticalDisagreement, // height or tilt differ from the graph's beyond the limits
  kInconsistent,         // the pose graph found it inconsistent with the other loops
};
const char* to_string(LoopOutcome outcome);

struct LoopCheck {
  LoopOutcome outcome = LoopOutcome::kNoCandidate;
  std::size_t current = 0;    // node indices
  std::size_t candidate = 0;
  double similarity_m = -1.0;
  double similarity_forward_m = -1.0;
  double similarity_backward_m = -1.0;
  double rms_m = 0.0;
  double inlier_fraction = 0.0;
  int degenerate_directions = 0;
  bool converged = false;
  double dz_m = 0.0;          // registered minus graph height of the current keyframe
  double tilt_deg = 0.0;      // angle between the registered and the graph's up axes
  double check_ms = 0.0;
  Eigen::Isometry3d registered = Eigen::Isometry3d::Identity();  // T_world_current from the registration
  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();    // T_candidate_current (the factor)
};

/// Body-frame points (a keyframe's clouds) at a pose in the world frame.
std::vector<Eigen::Vector3d> to_world(const std::vector<Eigen::Vector3f>& body, const Eigen::Isometry3d& pose);

/// A keyframe at a pose in the world frame.
struct PlacedKeyframe {
  std::shared_ptr<const BackendKeyframe> keyframe;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

/// A neighbourhood of keyframes in the world frame: the map a keyframe is registered on.
struct SubMap {
  std::vector<Eigen::Vector3d> similarity;
  LocalMap planes;
  LocalMap edges;
};
SubMap make_submap(const std::vector<PlacedKeyframe>& members, const AlgorithmConfig& config);

/// Steps 2-4 for `current` near `guess` (T_world_body) on `submap`: the similarity test (if
/// enabled) against the sub-map and `candidate_world` (the candidate's similarity cloud in the
/// world frame), registration, fit limits, and the vertical check against the guess. Fills the
/// outcome, the figures and `registered`; not the node indices nor `measured`.
LoopCheck verify_on_submap(const BackendKeyframe& current, const Eigen::Isometry3d& guess, const SubMap& submap,
                           const std::vector<Eigen::Vector3d>& candidate_world, const AlgorithmConfig& config);

/// Verifies one candidate: similarity (if enabled), registration of the current keyframe's
/// body points into the candidate's sub-map, fit limits, vertical check. `poses` are the graph's
/// current estimates; `keyframes` the stored keyframes, index = node (only the current one and
/// the candidate's sub-map are read, through the store's cache).
LoopCheck check_loop(KeyframeStore& keyframes, const std::vector<Eigen::Isometry3d>& poses, std::size_t current,
                     std::size_t candidate, const AlgorithmConfig& config);
/// The same on keyframes all in memory (tests).
LoopCheck check_loop(const std::vector<BackendKeyframe>& keyframes, const std::vector<Eigen::Isometry3d>& poses,
                     std::size_t current, std::size_t candidate, const AlgorithmConfig& config);

}  // namespace liod
