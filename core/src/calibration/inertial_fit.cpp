#include "liod/calibration/inertial_fit.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "liod/so3.hpp"

namespace liod::calibration {
namespace {

constexpr int kParams = 15;  // dθ, b_g, t, b_a, g
constexpr int kRot = 0;
constexpr int kGyroBias = 3;
constexpr int kTrans = 6;
constexpr int kAccelBias = 9;
constexpr int kGravity = 12;

/// One accelerometer residual's fixed parts: with M = R^T,
///   r = dp - D M t - G vec(M) + B M b_a - c g.
struct Triple {
  Eigen::Vector3d dp = Eigen::Vector3d::Zero();  // divided difference of the LiDAR's positions
  Eigen::Matrix3d d = Eigen::Matrix3d::Zero();   // the same of its rotations
  Eigen::Matrix<double, 3, 9> g = Eigen::Matrix<double, 3, 9>::Zero();  // ∫K R_wl(s) M f(s) = g vec(M)
  Eigen::Matrix3d b = Eigen::Matrix3d::Zero();   // ∫K R_wl(s) ds
  double c = 0.0;                                // ∫K ds
  double weight_share = 1.0;                     // 1 / the triples sharing its samples
};

struct Parameters {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, kParams, 1> x = Eigen::Matrix<double, kParams, 1>::Zero();  // dθ stays 0
};

Eigen::Vector3d interpolated_accel(const std::vector<ImuSample>& imu, std::size_t i, double time) {
  const double u = (time - imu[i].time) / (imu[i + 1].time - imu[i].time);
  return imu[i].accel + u * (imu[i + 1].accel - imu[i].accel);
}

/// The kernel's integrals over the IMU samples, piece by piece (midpoint rule, split at t1).
struct Rotations {
  const AttitudeTrack& track;
  const Eigen::Matrix3d& lidar_to_imu;
};

void integrate_triple(const std::vector<LidarPose>& poses, const std::vector<ImuSample>& imu, const Rotations& rot,
                      double t0, double t1, double t2, Triple& out) {
  auto first = std::upper_bound(imu.begin(), imu.end(), t0, [](double t, const ImuSample& s) { return t < s.time; });
  auto i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(first - imu.begin() - 1, 0));
  for (; i + 1 < imu.size() && imu[i].time < t2; ++i) {
    for (const auto& [lo, hi] : {std::pair{t0, t1}, std::pair{t1, t2}}) {
      const double a = std::max(lo, imu[i].time);
      const double b = std::min(hi, imu[i + 1].time);
      if (!(b > a)) continue;
      const double mid = 0.5 * (a + b);
      const double k = mid < t1 ? (mid - t0) / (t1 - t0) : (t2 - mid) / (t2 - t1);
      const double w = k * (b - a);
      const Eigen::Matrix3d r = lidar_rotation_at(poses, rot.track, rot.lidar_to_imu, mid);
      const Eigen::Vector3d f = interpolated_accel(imu, i, mid);
      for (int col = 0; col < 3; ++col) {
        out.g.middleCols<3>(3 * col) += w * f(col) * r;  // vec(M) is column-major: M(:, col) pairs with f(col)
      }
      out.b += w * r;
      out.c += w;
    }
  }
}

std::vector<Triple> make_triples(const std::vector<LidarPose>& poses, const std::vector<ImuSample>& imu,
                                 const Rotations& rot, const std::vector<double>& spacings_s) {
  std::vector<Triple> triples;
  if (poses.size() < 3 || imu.size() < 2) return triples;
  const double period = (poses.back().time - poses.front().time) / static_cast<double>(poses.size() - 1);
  for (const double spacing : spacings_s) {
    const auto m = static_cast<std::size_t>(std::max<long>(1, std::lround(spacing / period)));
    for (std::size_t k = m; k + m < poses.size(); ++k) {
      const LidarPose& p0 = poses[k - m];
      const LidarPose& p1 = poses[k];
      const LidarPose& p2 = poses[k + m];
      if (p0.time < imu.front().time || p2.time > imu.back().time) continue;
      const double h1 = p1.time - p0.time;
      const double h2 = p2.time - p1.time;
      Triple t;
      t.dp = (p2.position - p1.position) / h2 - (p1.position - p0.position) / h1;
      t.d = (p2.rotation - p1.rotation) / h2 - (p1.rotation - p0.rotation) / h1;
      t.weight_share = 1.0 / static_cast<double>(2 * m);
      integrate_triple(poses, imu, rot, p0.time, p1.time, p2.time, t);
      triples.push_back(t);
    }
  }
  return triples;
}

Eigen::Matrix<double, 9, 1> vec(const Eigen::Matrix3d& m) { return Eigen::Map<const Eigen::Matrix<double, 9, 1>>(m.data()); }

Eigen::Vector3d accel_residual(const Triple& t, const Eigen::Matrix3d& rotation, const Eigen::Matrix<double, kParams, 1>& x) {
  const Eigen::Matrix3d m = rotation.transpose();
  return t.dp - t.d * m * x.segment<3>(kTrans) - t.g * vec(m) + t.b * m * x.segment<3>(kAccelBias) - t.c * x.segment<3>(kGravity);
}

Eigen::Vector3d gyro_residual(const RatePair& p, const Eigen::Matrix3d& rotation, const Eigen::Matrix<double, kParams, 1>& x) {
  return p.gyro - x.segment<3>(kGyroBias) - rotation * p.lidar;
}

using Jacobian = Eigen::Matrix<double, 3, kParams>;

Jacobian accel_jacobian(const Triple& t, const Parameters& p) {
  Jacobian j = Jacobian::Zero();
  const Eigen::Matrix3d m = p.rotation.transpose();
  j.middleCols<3>(kTrans) = -t.d * m;
  j.middleCols<3>(kAccelBias) = t.b * m;
  j.middleCols<3>(kGravity) = -t.c * Eigen::Matrix3d::Identity();
  constexpr double kStep = 1e-6;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d step = kStep * Eigen::Vector3d::Unit(a);
    const Eigen::Vector3d plus = accel_residual(t, so3::exp(step) * p.rotation, p.x);
    const Eigen::Vector3d minus = accel_residual(t, so3::exp(-step) * p.rotation, p.x);
    j.col(kRot + a) = (plus - minus) / (2.0 * kStep);
  }
  return j;
}

Jacobian gyro_jacobian(const RatePair& pair, const Parameters& p) {
  Jacobian j = Jacobian::Zero();
  j.middleCols<3>(kRot) = so3::hat(p.rotation * pair.lidar);  // d(-exp(dθ) R w)/d(dθ) = [R w]x
  j.middleCols<3>(kGyroBias) = -Eigen::Matrix3d::Identity();
  return j;
}

struct Normal {
  Eigen::Matrix<double, kParams, kParams> h = Eigen::Matrix<double, kParams, kParams>::Zero();
  Eigen::Matrix<double, kParams, 1> b = Eigen::Matrix<double, kParams, 1>::Zero();
  double gyro_sq = 0.0;
  double accel_sq = 0.0;
};

struct Weights {
  double gyro_sigma = 1e-2;  // starting scatters; each round replaces them with the residuals' own
  double accel_sigma = 1e-2;
  const std::optional<LeverArmHold>& hold;
  double hold_sigma;
};

Normal build_normal(const std::vector<Triple>& triples, const std::vector<RatePair>& rates, const Parameters& p,
                    const Weights& weights) {
  Normal n;
  const double gyro_sigma = weights.gyro_sigma;
  const double accel_sigma = weights.accel_sigma;
  if (weights.hold) {
    Eigen::Matrix<double, 1, kParams> j = Eigen::Matrix<double, 1, kParams>::Zero();
    j.middleCols<3>(kTrans) = weights.hold->axis.transpose();
    const double r = weights.hold->axis.dot(p.x.segment<3>(kTrans)) - weights.hold->value;
    const double w = 1.0 / (weights.hold_sigma * weights.hold_sigma);
    n.h += w * j.transpose() * j;
    n.b -= w * j.transpose() * r;
  }
  for (const RatePair& pair : rates) {
    const Eigen::Vector3d r = gyro_residual(pair, p.rotation, p.x);
    const Jacobian j = gyro_jacobian(pair, p);
    const double w = 1.0 / (gyro_sigma * gyro_sigma);
    n.h += w * j.transpose() * j;
    n.b -= w * j.transpose() * r;
    n.gyro_sq += r.squaredNorm();
  }
  for (const Triple& t : triples) {
    const Eigen::Vector3d r = accel_residual(t, p.rotation, p.x);
    const Jacobian j = accel_jacobian(t, p);
    const double w = t.weight_share / (accel_sigma * accel_sigma);
    n.h += w * j.transpose() * j;
    n.b -= w * j.transpose() * r;
    n.accel_sq += r.squaredNorm();
  }
  return n;
}

}  // namespace

InertialFit fit_inertial(const std::vector<LidarPose>& poses, const std::vector<ImuSample>& imu,
                         const std::vector<RatePair>& rates, const RotationHandEye& initial,
                         const std::optional<LeverArmHold>& hold, const InertialFitConfig& config) {
  InertialFit fit;
  const AttitudeTrack track(imu, initial.gyro_bias);
  const Eigen::Matrix3d& initial_rotation = initial.lidar_to_imu;
  const std::vector<Triple> triples = make_triples(poses, imu, Rotations{track, initial_rotation}, config.spacings_s);
  if (triples.size() < 10 || rates.size() < 10) return fit;
  Parameters p;
  p.rotation = initial_rotation;
  Weights weights{.hold = hold, .hold_sigma = config.hold_std_m};
  Normal n;
  for (int round = 0; round < config.weighting_rounds; ++round) {
    for (int it = 0; it < config.iterations; ++it) {
      n = build_normal(triples, rates, p, weights);
      const Eigen::Matrix<double, kParams, 1> dx = n.h.ldlt().solve(n.b);
      if (!dx.allFinite()) return fit;
      p.rotation = so3::normalize(so3::exp(dx.segment<3>(kRot)) * p.rotation);
      p.x.tail<kParams - 3>() += dx.tail<kParams - 3>();
      if (dx.segment<3>(kRot).norm() < 1e-9 && dx.segment<3>(kTrans).norm() < 1e-7) break;
    }
    n = build_normal(triples, rates, p, weights);
    weights.gyro_sigma = std::max(1e-6, std::sqrt(n.gyro_sq / (3.0 * static_cast<double>(rates.size()))));
    weights.accel_sigma = std::max(1e-6, std::sqrt(n.accel_sq / (3.0 * static_cast<double>(triples.size()))));
  }
  n = build_normal(triples, rates, p, weights);
  const Eigen::Matrix<double, kParams, kParams> covariance = n.h.ldlt().solve(Eigen::Matrix<double, kParams, kParams>::Identity());
  fit.lidar_to_imu = p.rotation;
  fit.gyro_bias = p.x.segment<3>(kGyroBias);
  fit.translation = p.x.segment<3>(kTrans);
  fit.accel_bias = p.x.segment<3>(kAccelBias);
  fit.gravity = p.x.segment<3>(kGravity);
  fit.rotation_std = covariance.diagonal().segment<3>(kRot).cwiseMax(0.0).cwiseSqrt();
  fit.translation_std = covariance.diagonal().segment<3>(kTrans).cwiseMax(0.0).cwiseSqrt();
  fit.gyro_rms = weights.gyro_sigma;
  fit.accel_rms = weights.accel_sigma;
  fit.gyro_residuals = rates.size();
  fit.accel_residuals = triples.size();
  fit.valid = covariance.allFinite();
  return fit;
}

}  // namespace liod::calibration
