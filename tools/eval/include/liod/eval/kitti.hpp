#pragma once
// The KITTI odometry benchmark's metric, as the devkit's evaluate_odometry.cpp computes it:
// for every first frame in steps of 10 frames and every length L in 100, 200, ..., 800 m of ground-truth
// path, the last frame is the first one whose path distance from the first frame exceeds L (strictly);
// with the relative motions dG = G_f^-1 G_l and dE = E_f^-1 E_l, the error pose is dE^-1 dG, and the
// segment contributes |t_err| / L and angle(R_err) / L. The summary is the plain mean over all segments
// (every length together), reported as % and deg/100 m; segments that do not fit are skipped.
//
// Faithful to the devkit, including that a segment actually spans slightly more than L (up to one frame
// more) while its error is divided by L. Differences: double instead of float, and the angle via atan2
// (identical value, better precision for small angles; see rotation_angle()). Relative motions do not
// change under a rigid alignment of the estimate, so with --align none or se3 this is exactly the
// devkit's number; with sim3 the estimate's scale is corrected first, as monocular evaluations do.

#include <cstddef>
#include <optional>
#include <vector>

#include "liod/eval/trajectory.hpp"

namespace liod::eval {

struct KittiOptions {
  /// Frames of the (associated) sequence between first frames; the devkit's step_size.
  std::size_t step = 10;
  std::vector<double> lengths_m = {100, 200, 300, 400, 500, 600, 700, 800};
};

struct KittiSegment {
  std::size_t first_frame = 0;
  std::size_t last_frame = 0;
  double length_m = 0.0;
  double translation_ratio = 0.0;   // |t_err| / L
  double rotation_rad_per_m = 0.0;  // angle(R_err) / L
};

struct KittiLengthResult {
  double length_m = 0.0;
  std::size_t segments = 0;
  /// nullopt when no segment of this length fits.
  std::optional<double> translational_pct;
  std::optional<double> rotational_deg_per_100m;
};

struct KittiResult {
  KittiOptions options;
  double gt_length_m = 0.0;
  std::vector<KittiSegment> segments;
  std::vector<KittiLengthResult> per_length;
  /// nullopt when not a single segment fits (trajectory shorter than the shortest length).
  std::optional<double> translational_pct;
  std::optional<double> rotational_deg_per_100m;
};

/// gt and est pairwise corresponding (same frame i on both sides).
KittiResult kitti_odometry_error(const Poses& gt, const Poses& est, const KittiOptions& options = {});

}  // namespace liod::eval
