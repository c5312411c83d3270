#pragma once
// The odometry factor between consecutive keyframes, weighted by the front end's covariance
// (LIO-SAM weighs its LiDAR odometry factors with fixed sigmas; issue: a scan-to-map filter knows
// how well each keyframe was registered, and a loop's correction belongs where it was not).
// The filter's pose covariance at each keyframe, [dtheta (right perturbation, body), dp (world)],
// is carried into the relative pose T_i^-1 T_j to first order; the two keyframes' errors are
// taken as independent, which overstates the increment's uncertainty where the window's map ties
// them and never understates it.

#include <Eigen/Core>

#include "liod/backend/pose_graph.hpp"
#include "liod/imu_preintegration.hpp"
#include "liod/keyframe.hpp"  // PoseCovariance

namespace liod {

/// Covariance of the relative pose of b seen from a, in PoseGraph's residual order
/// [translation, rotation].
Matrix6d relative_pose_covariance(const NavState& a, const PoseCovariance& a_covariance, const NavState& b,
                                  const PoseCovariance& b_covariance);

/// The information of that covariance, with a floor on its diagonal (floor_translation_m,
/// floor_rotation_rad as sigmas): a filter's covariance can be near singular in a direction the
/// map pins, and one factor must not outweigh the rest of the graph by orders of magnitude.
Matrix6d relative_pose_information(const Matrix6d& covariance, double floor_translation_m, double floor_rotation_rad);

}  // namespace liod
