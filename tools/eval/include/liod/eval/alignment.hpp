#pragma once
// Aligning the estimate to the ground truth before absolute errors are taken.
// An odometry estimate lives in its own world frame (its start pose), so absolute errors only mean
// something after the rigid (SE(3)) or, for monocular scale ambiguity, similarity (Sim(3)) transform
// that best maps estimate positions onto ground-truth positions is applied.

#include <Eigen/Core>
#include <cstddef>
#include <string>

#include "liod/eval/trajectory.hpp"

namespace liod::eval {

enum class AlignMode { None, SE3, Sim3 };
AlignMode parse_align_mode(const std::string& text);  // none | se3 | sim3; throws InputError
const char* to_string(AlignMode mode);

/// y ≈ scale * R * x + t.
struct Similarity {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double scale = 1.0;
  /// The rotation is not unique: the points are collinear (or coincide), so any roll about their
  /// line fits equally well. Translation errors are still right; rotation errors are arbitrary.
  bool degenerate = false;
};

/// Least-squares similarity (with_scale) or rigid motion mapping columns of x onto columns of y:
/// S. Umeyama, "Least-squares estimation of transformation parameters between two point patterns",
/// IEEE TPAMI 13(4), 1991. Needs at least one point pair; x and y have the same number of columns.
Similarity umeyama(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& y, bool with_scale);

struct AlignmentOptions {
  AlignMode mode = AlignMode::SE3;
  /// 0: fit on all pairs. 1: make the first estimate pose coincide with the first ground-truth pose
  /// (position and orientation; one point cannot fix a rotation). N >= 2: Umeyama on the first N pairs,
  /// so the error grows with distance from the start, as in drift studies.
  std::size_t first_n = 0;
};

struct Alignment {
  AlignmentOptions options;
  Similarity transform;
  std::size_t pairs_used = 0;
};

/// Finds the alignment of est onto gt (pairwise corresponding poses). Throws InputError when the
/// request cannot be met (Sim(3) from one pose).
Alignment align(const Poses& gt, const Poses& est, const AlignmentOptions& options);

/// Applies T to every pose: R_i' = R R_i, p_i' = s R p_i + t (evo's convention: scale moves positions only).
Poses apply_similarity(const Similarity& T, const Poses& poses);

}  // namespace liod::eval
