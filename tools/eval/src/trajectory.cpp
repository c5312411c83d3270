#include "liod/eval/trajectory.hpp"

#include <cmath>

namespace liod::eval {

std::vector<double> path_distances(const Poses& poses) {
  std::vector<double> d;
  d.reserve(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    d.push_back(i == 0 ? 0.0 : d.back() + (poses[i].translation() - poses[i - 1].translation()).norm());
  }
  return d;
}

double rotation_angle(const Eigen::Matrix3d& R) {
  const Eigen::Vector3d axis_sin(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  const double s = 0.5 * axis_sin.norm();
  const double c = 0.5 * (R.trace() - 1.0);
  return std::atan2(s, c);
}

}  // namespace liod::eval
