#pragma once
// Pairing estimate poses with ground-truth poses.
//
// Nearest: like evo's `associate` (nearest stamp within max_dt), but one-to-one and monotone: evo may
// give one ground-truth pose to two estimates; here a ground-truth pose is used at most once, by the
// estimate closest to it in time, so the pairs are in time order on both sides.
//
// Interpolated: the ground truth is interpolated (slerp on rotation, linear on position) at each
// estimate's stamp. When the ground truth is denser than the estimate (200 Hz INS against 10 Hz
// LiDAR), the nearest ground-truth pose is up to half a ground-truth period away from the estimate's
// instant; at 15 m/s and 100 Hz that is 7.5 cm of error that belongs to nobody. Interpolating removes
// it. An estimate stamp is only paired when it lies between two ground-truth stamps no more than
// max_gap apart: we never extrapolate, and never bridge a dropout.

#include <cstddef>
#include <string>
#include <vector>

#include "liod/eval/trajectory.hpp"

namespace liod::eval {

enum class Interpolation { Auto, On, Off };
Interpolation parse_interpolation(const std::string& text);  // auto | on | off; throws InputError

struct AssociationOptions {
  /// Nearest mode: largest |t_gt - t_est| accepted, seconds.
  double max_dt = 0.02;
  /// Interpolated mode: largest ground-truth interval to interpolate across, seconds.
  double max_gap = 0.1;
  /// Added to every estimate stamp before pairing (evo's --t_offset).
  double est_time_offset = 0.0;
  /// Auto: interpolate when the ground truth's median period is below 0.75 of the estimate's.
  Interpolation interpolation = Interpolation::Auto;
};

struct Association {
  /// Estimate stamps (after the offset) of the pairs; frame indices when pairing by index.
  std::vector<double> stamps;
  Poses gt;
  Poses est;
  /// Index into the estimate file of every pair (for reports and plots).
  std::vector<std::size_t> est_index;
  bool by_time = true;
  bool interpolated = false;
};

/// Pairs by stamps when both have them, else by index (KITTI), which requires equal lengths.
/// Throws InputError when nothing pairs.
Association associate(const Trajectory& gt, const Trajectory& est, const AssociationOptions& options);

/// Pose at fraction u in [0,1] from a to b: slerp on rotation, linear on translation.
Eigen::Isometry3d interpolate(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double u);

/// Median of consecutive stamp differences; 0 for fewer than two stamps.
double median_period(const std::vector<double>& stamps);

}  // namespace liod::eval
