#pragma once
// What the fault tests measure on the published poses, against the drive's ground truth.

#include <cstdint>
#include <vector>

#include "liod/daemon/pose_protocol.hpp"
#include "liod/eval/trajectory.hpp"

namespace liod::test {

struct Accuracy {
  double rmse_m = 0.0;
  double max_m = 0.0;
  std::size_t poses = 0;
};
/// Absolute trajectory error of the scan poses in [from, to), after one SE(3) alignment of all
/// scan poses on the ground truth (liod-eval's ATE, restricted to a window).
Accuracy scan_accuracy(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth, double from,
                       double to);

/// The same with the alignment itself on the scan poses in [from, to) only: the accuracy in a
/// frame of its own (after a re-initialisation the odometry's new map lies where the dead
/// reckoning left it). `ok_only`: of the poses flagged ok only.
Accuracy scan_accuracy_within(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth, double from,
                              double to, bool ok_only = false);

/// How far the first scan pose at or after `t` is from the truth, in the frame of the scan poses
/// in [from, to) aligned on the truth (SE(3)): e.g. the dead reckoning's error over an outage.
double position_error_after(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth, double from,
                            double to, double t);

struct Jump {
  double position_m = 0.0;   ///< | |dp estimated| - |dp true| |
  double rotation_deg = 0.0; ///< | angle turned estimated - angle turned true |
  double at = 0.0;           ///< time of the later pose of the worst position step
};
/// The worst step between consecutive published poses (both rates, in publish order) beyond
/// what the vehicle really moved between the same instants: a wild pose shows here. Pairs with an
/// initialising pose are left out: its position means nothing yet (docs/pose-protocol.md).
/// `with_initializing`: initialising poses count too, and only pairs whose earlier pose is at or
/// after `from`.
Jump largest_jump(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth,
                  bool with_initializing = false, double from = -1e300);

/// The largest angle between the scan poses' rotation since the first scan pose and the truth's
/// over the same time (deg): how far the attitude, mostly the heading, drifted.
double largest_attitude_drift_deg(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth);

struct FlagCount {
  std::size_t poses = 0;
  std::size_t flagged = 0;
};
/// Poses of `type` with time in [from, to), and how many of them carry `flag`.
FlagCount count_flag(const std::vector<pose::PoseMessage>& poses, pose::MessageType type, std::uint32_t flag,
                     double from, double to);

}  // namespace liod::test
