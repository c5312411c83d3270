#include "liod/backend/pose_graph.hpp"

#include <ceres/ceres.h>
#include <ceres/version.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "imu_factor.hpp"

namespace liod {
namespace {

// Ceres 2.1 replaced LocalParameterization with Manifold; Ubuntu 22.04 ships 2.0, 20.04 ships 1.14.
#if CERES_VERSION_MAJOR > 2 || (CERES_VERSION_MAJOR == 2 && CERES_VERSION_MINOR >= 1)
#define LIOD_CERES_HAS_MANIFOLD 1
#else
#define LIOD_CERES_HAS_MANIFOLD 0
#endif

// Relative-pose residual (as in Ceres' pose_graph_3d example, Kümmerle et al. g2o's SE(3) edge):
//   q_ab_est = q_a^-1 q_b,  p_ab_est = q_a^-1 (p_b - p_a),
//   r = L [p_ab_est - p_ab_meas; 2 vec(q_ab_meas q_ab_est^-1)]   with L^T L = information.
struct RelativePoseError {
  RelativePoseError(const Eigen::Isometry3d& measured, const Matrix6d& sqrt_information)
      : q_ab(Eigen::Quaterniond(measured.linear()).normalized()), p_ab(measured.translation()), sqrt_info(sqrt_information) {}

  template <typename T>
  bool operator()(const T* qa_ptr, const T* pa_ptr, const T* qb_ptr, const T* pb_ptr, T* residual_ptr) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(qa_ptr);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(pa_ptr);
    const Eigen::Map<const Eigen::Quaternion<T>> q_b(qb_ptr);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_b(pb_ptr);
    const Eigen::Quaternion<T> q_a_inverse = q_a.conjugate();
    const Eigen::Quaternion<T> q_ab_estimated = q_a_inverse * q_b;
    const Eigen::Matrix<T, 3, 1> p_ab_estimated = q_a_inverse * (p_b - p_a);
    const Eigen::Quaternion<T> delta = q_ab.template cast<T>() * q_ab_estimated.conjugate();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual_ptr);
    r.template head<3>() = p_ab_estimated - p_ab.template cast<T>();
    r.template tail<3>() = T(2.0) * delta.vec();
    r.applyOnTheLeft(sqrt_info.template cast<T>());
    return true;
  }

  Eigen::Quaterniond q_ab;
  Eigen::Vector3d p_ab;
  Matrix6d sqrt_info;
};

// Tilt residual: the world's up axis seen from the body, R^T e_z, against the front end's.
// Yaw does not enter (rotation about e_z leaves R^T e_z unchanged), which is what lets a loop
// correct heading while gravity keeps roll and pitch.
struct TiltError {
  TiltError(const Eigen::Vector3d& up, double sigma) : up_in_body(up), inverse_sigma(1.0 / sigma) {}
  template <typename T>
  bool operator()(const T* q_ptr, T* residual_ptr) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_ptr);
    const Eigen::Matrix<T, 3, 1> up = q.conjugate() * Eigen::Matrix<T, 3, 1>(T(0), T(0), T(1));
    Eigen::Map<Eigen::Matrix<T, 3, 1>> r(residual_ptr);
    r = (up - up_in_body.template cast<T>()) * T(inverse_sigma);
    return true;
  }
  Eigen::Vector3d up_in_body;
  double inverse_sigma;
};

Matrix6d sqrt_information(const Matrix6d& information) {
  // L with L^T L = information: the transposed lower Cholesky factor.
  const Eigen::LLT<Matrix6d> llt(information);
  return llt.matrixL().transpose();
}

}  // namespace

Matrix6d relative_pose_information(double translation_sigma_m, double rotation_sigma_rad) {
  Matrix6d info = Matrix6d::Zero();
  info.diagonal().head<3>().setConstant(1.0 / (translation_sigma_m * translation_sigma_m));
  info.diagonal().tail<3>().setConstant(1.0 / (rotation_sigma_rad * rotation_sigma_rad));
  return info;
}

std::size_t PoseGraph::add_node(const Eigen::Isometry3d& initial) {
  poses_.push_back(initial);
  motions_.emplace_back();
  tilt_up_.emplace_back(Eigen::Vector3d::Zero());
  tilt_sigma_.push_back(0.0);
  return poses_.size() - 1;
}

void PoseGraph::set_tilt(std::size_t node, const Eigen::Vector3d& up_in_body, double sigma_rad) {
  tilt_up_[node] = up_in_body.normalized();
  tilt_sigma_[node] = sigma_rad;
}

void PoseGraph::add_factor(const PoseGraphFactor& factor) { factors_.push_back(factor); }

double PoseGraph::whitened_error(const PoseGraphFactor& f) const {
  const RelativePoseError error(f.measured, sqrt_information(f.information));
  const Eigen::Quaterniond qa(poses_[f.from].linear());
  const Eigen::Quaterniond qb(poses_[f.to].linear());
  const Eigen::Vector3d pa = poses_[f.from].translation();
  const Eigen::Vector3d pb = poses_[f.to].translation();
  Eigen::Matrix<double, 6, 1> r;
  error(qa.coeffs().data(), pa.data(), qb.coeffs().data(), pb.data(), r.data());
  return r.norm();
}

Eigen::Matrix<double, 9, 1> PoseGraph::whitened_error(const ImuGraphFactor& f) const {
  const ImuError error(f);
  const Eigen::Quaterniond qa(poses_[f.from].linear());
  const Eigen::Quaterniond qb(poses_[f.to].linear());
  const Eigen::Vector3d pa = poses_[f.from].translation();
  const Eigen::Vector3d pb = poses_[f.to].translation();
  const NodeMotion& ma = motions_[f.from];
  const NodeMotion& mb = motions_[f.to];
  Eigen::Matrix<double, 6, 1> ba, bb;
  ba << ma.gyro_bias, ma.accel_bias;
  bb << mb.gyro_bias, mb.accel_bias;
  Eigen::Matrix<double, 15, 1> r;
  error(qa.coeffs().data(), pa.data(), ma.velocity.data(), ba.data(), qb.coeffs().data(), pb.data(), mb.velocity.data(),
        bb.data(), r.data());
  return r.head<9>();
}

SolveReport PoseGraph::optimize(RobustLoss loss, double scale, int max_iterations, std::size_t first_free) {
  const auto start = std::chrono::steady_clock::now();
  SolveReport report;
  if (loss == RobustLoss::kCauchy && scale > 0.0) {
    // Graduated robustness: the convex Huber kernel first, so that every loop pulls with a
    // bounded force from a far-off start, then the redescending Cauchy kernel, under which a loop
    // that the others contradict loses its influence (Cauchy alone, started far away, can
    // ignore true loops as well).
    const SolveReport huber = solve(RobustLoss::kHuber, scale, max_iterations, first_free);
    report = solve(RobustLoss::kCauchy, scale, max_iterations, first_free);
    report.initial_cost = huber.initial_cost;
    report.iterations += huber.iterations;
  } else {
    report = solve(loss, scale, max_iterations, first_free);
  }
  report.solve_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return report;
}

namespace {

// Scales are in sigmas of the whitened residual; Ceres' kernels take the squared norm, so the
// parameter is the scale itself (rho(s) = a^2 log(1 + s / a^2) for Cauchy). None below 0.
ceres::LossFunction* robust_loss(RobustLoss loss, double scale) {
  if (scale <= 0.0) return nullptr;
  if (loss == RobustLoss::kHuber) return new ceres::HuberLoss(scale);
  if (loss == RobustLoss::kCauchy) return new ceres::CauchyLoss(scale);
  return nullptr;
}

ceres::Solver::Summary run_solver(ceres::Problem& problem, int max_iterations) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;  // the backend is one low-priority thread; also keeps replays deterministic
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return summary;
}

}  // namespace

namespace {

// One solve's Ceres problem over copies of the graph's states: a node enters it once, free nodes
// with their manifold and tilt factor, held ones (node 0, the prior that fixes the gauge, and in a
// windowed solve the nodes before the window, where the factors into the window anchor it) as
// constants. Velocity and biases enter with the first IMU factor that reaches the node.
class GraphProblem {
 public:
  GraphProblem(const std::vector<Eigen::Isometry3d>& poses, const std::vector<NodeMotion>& motions,
               const std::vector<Eigen::Vector3d>& tilt_up, const std::vector<double>& tilt_sigma, std::size_t first_free)
      : q_(poses.size()), p_(poses.size()), v_(poses.size()), b_(poses.size()), added_(poses.size(), 0),
        motion_added_(poses.size(), 0), tilt_up_(tilt_up), tilt_sigma_(tilt_sigma), first_free_(first_free),
        problem_(problem_options()) {
    for (std::size_t i = 0; i < poses.size(); ++i) {
      q_[i] = Eigen::Quaterniond(poses[i].linear()).normalized();
      p_[i] = poses[i].translation();
      v_[i] = motions[i].velocity;
      b_[i] << motions[i].gyro_bias, motions[i].accel_bias;
    }
  }

  void add_node(std::size_t i) {
    if (added_[i]) return;
    added_[i] = 1;
    problem_.AddParameterBlock(q_[i].coeffs().data(), 4);
    problem_.AddParameterBlock(p_[i].data(), 3);
    if (i < first_free_) {
      problem_.SetParameterBlockConstant(q_[i].coeffs().data());
      problem_.SetParameterBlockConstant(p_[i].data());
      return;
    }
#if LIOD_CERES_HAS_MANIFOLD
    problem_.SetManifold(q_[i].coeffs().data(), &quaternion_manifold_);
#else
    problem_.SetParameterization(q_[i].coeffs().data(), &quaternion_manifold_);
#endif
    if (tilt_sigma_[i] > 0.0) {
      problem_.AddResidualBlock(new ceres::AutoDiffCostFunction<TiltError, 3, 4>(new TiltError(tilt_up_[i], tilt_sigma_[i])),
                                nullptr, q_[i].coeffs().data());
    }
  }

  void add_factor(const PoseGraphFactor& f, ceres::LossFunction* robust) {
    add_node(f.from);
    add_node(f.to);
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseError, 6, 4, 3, 4, 3>(
        new RelativePoseError(f.measured, sqrt_information(f.information)));
    problem_.AddResidualBlock(cost, robust, q_[f.from].coeffs().data(), p_[f.from].data(), q_[f.to].coeffs().data(),
                              p_[f.to].data());
  }

  void add_imu_factor(const ImuGraphFactor& f) {
    add_node(f.from);
    add_node(f.to);
    add_motion(f.from);
    add_motion(f.to);
    auto* cost = new ceres::AutoDiffCostFunction<ImuError, 15, 4, 3, 3, 6, 4, 3, 3, 6>(new ImuError(f));
    problem_.AddResidualBlock(cost, nullptr, q_[f.from].coeffs().data(), p_[f.from].data(), v_[f.from].data(),
                              b_[f.from].data(), q_[f.to].coeffs().data(), p_[f.to].data(), v_[f.to].data(),
                              b_[f.to].data());
  }

  ceres::Problem& problem() { return problem_; }

  /// The free nodes' solution into the graph's states.
  void read_back(std::vector<Eigen::Isometry3d>& poses, std::vector<NodeMotion>& motions) const {
    for (std::size_t i = 0; i < poses.size(); ++i) {
      if (i >= first_free_) {
        poses[i].linear() = q_[i].normalized().toRotationMatrix();
        poses[i].translation() = p_[i];
      }
      if (!motion_added_[i]) continue;
      motions[i].velocity = v_[i];
      motions[i].gyro_bias = b_[i].head<3>();
      motions[i].accel_bias = b_[i].tail<3>();
    }
  }

 private:
  static ceres::Problem::Options problem_options() {
    ceres::Problem::Options options;
#if LIOD_CERES_HAS_MANIFOLD
    options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
#else
    options.local_parameterization_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
#endif
    return options;
  }

  void add_motion(std::size_t i) {
    if (motion_added_[i]) return;
    motion_added_[i] = 1;
    problem_.AddParameterBlock(v_[i].data(), 3);
    problem_.AddParameterBlock(b_[i].data(), 6);
    // Node 0's pose is the gauge, not its velocity and biases: those the IMU factors estimate. A
    // windowed solve holds what lies before the window as it is.
    if (i < first_free_ && first_free_ > 1) {
      problem_.SetParameterBlockConstant(v_[i].data());
      problem_.SetParameterBlockConstant(b_[i].data());
    }
  }

  std::vector<Eigen::Quaterniond> q_;  // Eigen's layout (x, y, z, w)
  std::vector<Eigen::Vector3d> p_;
  std::vector<Eigen::Vector3d> v_;
  std::vector<Eigen::Matrix<double, 6, 1>> b_;  // (b_g, b_a)
  std::vector<char> added_;
  std::vector<char> motion_added_;
  const std::vector<Eigen::Vector3d>& tilt_up_;
  const std::vector<double>& tilt_sigma_;
  std::size_t first_free_;
#if LIOD_CERES_HAS_MANIFOLD
  ceres::EigenQuaternionManifold quaternion_manifold_;
#else
  ceres::EigenQuaternionParameterization quaternion_manifold_;
#endif
  ceres::Problem problem_;
};

}  // namespace

SolveReport PoseGraph::solve(RobustLoss loss, double scale, int max_iterations, std::size_t first_free) {
  SolveReport report;
  first_free = std::max<std::size_t>(first_free, 1);  // node 0 is the prior: always held
  if (poses_.size() <= first_free) return report;
  report.nodes = poses_.size() - first_free;

  GraphProblem graph(poses_, motions_, tilt_up_, tilt_sigma_, first_free);
  if (first_free == 1) graph.add_node(0);  // the full graph: blocks in node order
  for (std::size_t i = first_free; i < poses_.size(); ++i) graph.add_node(i);
  for (const auto& f : factors_) {
    if (f.from < first_free && f.to < first_free) continue;  // between held nodes: a constant
    ++report.factors;
    graph.add_factor(f, f.loop ? robust_loss(loss, scale) : nullptr);
  }
  for (const auto& f : imu_factors_) {
    if (f.from < first_free && f.to < first_free) continue;
    ++report.imu_factors;
    graph.add_imu_factor(f);
  }

  const ceres::Solver::Summary summary = run_solver(graph.problem(), max_iterations);
  graph.read_back(poses_, motions_);
  report.iterations = static_cast<int>(summary.iterations.size());
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  report.converged = summary.termination_type == ceres::CONVERGENCE;
  return report;
}

void PoseGraph::transform(const Eigen::Isometry3d& delta) {
  for (std::size_t k = 0; k < poses_.size(); ++k) {
    poses_[k] = delta * poses_[k];
    motions_[k].velocity = delta.linear() * motions_[k].velocity;
  }
  for (auto& f : imu_factors_) f.gravity = delta.linear() * f.gravity;
}

}  // namespace liod
