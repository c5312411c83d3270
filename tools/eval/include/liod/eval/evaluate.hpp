#pragma once
// One evaluation: associate, align, then every metric on the same pairs.

#include <optional>
#include <string>
#include <vector>

#include "liod/eval/alignment.hpp"
#include "liod/eval/association.hpp"
#include "liod/eval/kitti.hpp"
#include "liod/eval/metrics.hpp"
#include "liod/eval/trajectory.hpp"

namespace liod::eval {

struct EvalOptions {
  AssociationOptions association;
  AlignmentOptions alignment;
  RpeOptions rpe;
  KittiOptions kitti;
  /// The ground truth frame's vertical, for the ATE's split (liod and TUM: z; KITTI's camera: -y).
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
};

struct EvalResult {
  std::string gt_name;
  std::string est_name;
  std::size_t gt_poses = 0;
  std::size_t est_poses = 0;
  AssociationOptions association_options;
  Association association;
  Alignment alignment;
  /// The estimate of each pair after alignment.
  Poses est_aligned;
  AteResult ate;
  /// nullopt when the ground truth never moves horizontally (no direction of travel).
  std::optional<AteSplit> ate_split;
  std::optional<RpeResult> rpe;
  KittiResult kitti;
  /// Ground-truth path length over the paired poses.
  double length_m = 0.0;
  /// Distance travelled by the unaligned estimate against the ground truth's, in 1 m steps.
  std::optional<DistanceResult> distance;
  /// Time span of the pairs; nullopt when paired by index.
  std::optional<double> duration_s;
  /// Things the reader of the numbers must know (degenerate alignment, metric not computable, ...).
  std::vector<std::string> notes;
};

EvalResult evaluate(const Trajectory& gt, const Trajectory& est, const EvalOptions& options);

}  // namespace liod::eval
