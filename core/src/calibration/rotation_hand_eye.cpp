#include "liod/calibration/rotation_hand_eye.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>

namespace liod::calibration {

RotationHandEye rotation_from_rates(const std::vector<RatePair>& pairs) {
  RotationHandEye result;
  if (pairs.size() < 3) return result;
  const auto n = static_cast<double>(pairs.size());
  Eigen::Vector3d mean_lidar = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_gyro = Eigen::Vector3d::Zero();
  for (const RatePair& p : pairs) {
    mean_lidar += p.lidar;
    mean_gyro += p.gyro;
  }
  mean_lidar /= n;
  mean_gyro /= n;
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  for (const RatePair& p : pairs) {
    const Eigen::Vector3d l = p.lidar - mean_lidar;
    cross += l * (p.gyro - mean_gyro).transpose();
    spread += l * l.transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  // A reflection is no rotation: flip the weakest direction instead.
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  result.lidar_to_imu = svd.matrixV() * d * svd.matrixU().transpose();
  result.gyro_bias = mean_gyro - result.lidar_to_imu * mean_lidar;

  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(spread / n);
  result.rate_spread = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  result.spread_axes = result.lidar_to_imu * eig.eigenvectors();
  double sum = 0.0;
  for (const RatePair& p : pairs) {
    sum += (p.gyro - result.gyro_bias - result.lidar_to_imu * p.lidar).squaredNorm();
  }
  result.residual_rms = std::sqrt(sum / (3.0 * n));
  result.valid = true;
  return result;
}

}  // namespace liod::calibration
