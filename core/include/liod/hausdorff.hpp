#pragma once
// Bidirectional Hausdorff distance H(A,B) = max(h(A,B), h(B,A)), h(A,B) = max_a min_b ||a - b||
// (the seed paper, keyframe gating and loop-closure similarity). Computed on downsampled clouds with
// a voxel hash; distances are saturated at `cap`, which is all a threshold test needs.

#include <Eigen/Core>
#include <vector>

namespace liod {

/// h(A,B), saturated at cap.
double directed_hausdorff(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, double cap);

/// H(A,B), saturated at cap. Empty clouds give cap.
double hausdorff_distance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, double cap);

}  // namespace liod
