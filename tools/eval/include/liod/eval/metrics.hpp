#pragma once
// Absolute and relative trajectory errors, defined as evo defines them (Grupp, evo, metrics.py) so
// numbers can be compared with papers that used evo.

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "liod/eval/trajectory.hpp"

namespace liod::eval {

/// Summary of a list of errors, as evo reports it: std is the population deviation (numpy's default),
/// median averages the two middle values of an even count.
struct Stats {
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double std = 0.0;
  double min = 0.0;
  double max = 0.0;
  std::size_t count = 0;
};

/// nullopt for an empty list: no statistic beats a made-up one.
std::optional<Stats> summarize(std::vector<double> values);

struct AteResult {
  /// |p_est_i - p_gt_i| per pair, metres (after alignment).
  std::vector<double> translation_m;
  /// angle(R_gt_i^T R_est_i) per pair, degrees.
  std::vector<double> rotation_deg;
  Stats translation;
  Stats rotation;
};

/// gt and est pairwise corresponding and non-empty; est already aligned.
AteResult compute_ate(const Poses& gt, const Poses& est);

/// The ATE's translation error split in the ground truth's frame of travel, signed: along the
/// direction of travel (the mean says whether the estimate runs ahead), across it (positive to the
/// left of travel), and along `up`. A vehicle's error budget reads differently per axis: along the
/// track it is the speed, across it the heading, vertically the map's pitch.
struct AteSplit {
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  Stats along;
  Stats across;
  Stats vertical;
};

/// Direction of travel at pair i: the ground truth's horizontal (perpendicular to `up`) motion
/// between its neighbours; where it stands still (under kMinTravelForHeading), the nearest
/// direction before it, else after it. nullopt when the ground truth never moves horizontally.
/// gt and est as for compute_ate; `up` a unit vector in the ground truth's frame.
std::optional<AteSplit> compute_ate_split(const Poses& gt, const Poses& est, const Eigen::Vector3d& up);
inline constexpr double kMinTravelForHeading = 0.05;  // m between a pair's two neighbours

enum class DeltaUnit { Metres, Seconds, Frames };
DeltaUnit parse_delta_unit(const std::string& text);  // m | s | frames; throws InputError
const char* to_string(DeltaUnit unit);

struct RpeOptions {
  double delta = 1.0;
  DeltaUnit unit = DeltaUnit::Seconds;
};

/// Consecutive (non-overlapping) pairs (i, j) spaced by delta:
///  - frames: i = 0, d, 2d, ... (evo's filter_pairs_by_index);
///  - metres: evo's filter_pairs_by_path on the ground truth: an index is taken each time the path
///    accumulated since the last taken index reaches delta (the first at the first crossing);
///  - seconds (not in evo, which has no time unit): from index 0, the next index is the first whose
///    stamp is at least delta later (1 us slack so 10 Hz stamps written as decimals still count).
std::vector<std::pair<std::size_t, std::size_t>> rpe_pairs(const std::vector<double>& stamps, const Poses& gt,
                                                            const RpeOptions& options);

struct RpeResult {
  RpeOptions options;
  std::size_t pairs = 0;
  Stats translation;  // metres
  Stats rotation;     // degrees
};

/// E_ij = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j), Q ground truth, P estimate (evo's RPE); the translation error
/// is |trans(E)| and the rotation error angle(rot(E)). nullopt when no pair fits (trajectory shorter
/// than delta).
std::optional<RpeResult> compute_rpe(const std::vector<double>& stamps, const Poses& gt, const Poses& est,
                                     const RpeOptions& options);

/// Distance travelled by each trajectory, summed over steps of at least `step_m` of ground-truth
/// path (rpe_pairs in metres): a scale error of the estimate shows as its percentage, where the ATE
/// after alignment hides most of it; a standstill's jitter adds nothing. est unaligned (lengths do
/// not change under a rigid motion, a Sim(3) alignment would scale them).
struct DistanceResult {
  double step_m = 1.0;
  std::size_t steps = 0;
  double ground_truth_m = 0.0;
  double estimate_m = 0.0;
  /// 100 (estimate / ground truth - 1): negative when the estimate came out short.
  double error_pct = 0.0;
};

/// nullopt when the ground truth never travels step_m.
std::optional<DistanceResult> compute_distance_travelled(const Poses& gt, const Poses& est, double step_m = 1.0);

}  // namespace liod::eval
