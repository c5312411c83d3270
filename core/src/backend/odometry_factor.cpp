#include "liod/backend/odometry_factor.hpp"

#include <Eigen/Cholesky>

#include "liod/so3.hpp"

namespace liod {

// T_ab = T_a^-1 T_b with T = (R exp(dtheta), p + dp):
//   dt_ab = R_a^T (dp_b - dp_a) + [t_ab]x dtheta_a,   dphi_ab (right) = dtheta_b - R_ab^T dtheta_a.
// PoseGraph's rotation residual, 2 vec(q_measured q_estimated^-1), is -R_ab dphi_ab to first order.
Matrix6d relative_pose_covariance(const NavState& a, const PoseCovariance& a_covariance, const NavState& b,
                                  const PoseCovariance& b_covariance) {
  const Eigen::Matrix3d r_ab = a.rotation.transpose() * b.rotation;
  const Eigen::Vector3d t_ab = a.rotation.transpose() * (b.position - a.position);
  Matrix6d j_a = Matrix6d::Zero();  // d[dt, r_rotation] / d[dtheta_a, dp_a]
  j_a.block<3, 3>(0, 0) = so3::hat(t_ab);
  j_a.block<3, 3>(0, 3) = -a.rotation.transpose();
  j_a.block<3, 3>(3, 0) = Eigen::Matrix3d::Identity();  // -R_ab (-R_ab^T)
  Matrix6d j_b = Matrix6d::Zero();  // d[dt, r_rotation] / d[dtheta_b, dp_b]
  j_b.block<3, 3>(0, 3) = a.rotation.transpose();
  j_b.block<3, 3>(3, 0) = -r_ab;
  const Matrix6d covariance = j_a * a_covariance * j_a.transpose() + j_b * b_covariance * j_b.transpose();
  return 0.5 * (covariance + covariance.transpose());
}

Matrix6d relative_pose_information(const Matrix6d& covariance, double floor_translation_m, double floor_rotation_rad) {
  Matrix6d floored = covariance;
  floored.diagonal().head<3>().array() += floor_translation_m * floor_translation_m;
  floored.diagonal().tail<3>().array() += floor_rotation_rad * floor_rotation_rad;
  const Matrix6d information = floored.ldlt().solve(Matrix6d::Identity());
  return 0.5 * (information + information.transpose());
}

}  // namespace liod
