#include "liod/eval/alignment.hpp"

#include <Eigen/SVD>
#include <algorithm>

#include "liod/eval/io.hpp"

namespace liod::eval {

AlignMode parse_align_mode(const std::string& text) {
  if (text == "none") return AlignMode::None;
  if (text == "se3") return AlignMode::SE3;
  if (text == "sim3") return AlignMode::Sim3;
  throw InputError("unknown alignment '" + text + "' (want none, se3 or sim3)");
}

const char* to_string(AlignMode mode) {
  switch (mode) {
    case AlignMode::None: return "none";
    case AlignMode::SE3: return "se3";
    case AlignMode::Sim3: return "sim3";
  }
  return "none";
}

Similarity umeyama(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& y, bool with_scale) {
  const auto n = static_cast<double>(x.cols());
  // Eq. (34), (35): centroids.
  const Eigen::Vector3d mu_x = x.rowwise().mean();
  const Eigen::Vector3d mu_y = y.rowwise().mean();
  const Eigen::Matrix3Xd xc = x.colwise() - mu_x;
  const Eigen::Matrix3Xd yc = y.colwise() - mu_y;
  // Eq. (36): variance of x about its centroid.
  const double sigma2_x = xc.squaredNorm() / n;
  // Eq. (38): cross-covariance Sigma_xy = 1/n sum (y_i - mu_y)(x_i - mu_x)^T.
  const Eigen::Matrix3d sigma_xy = yc * xc.transpose() / n;

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma_xy, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& U = svd.matrixU();
  const Eigen::Matrix3d& V = svd.matrixV();
  const Eigen::Vector3d D = svd.singularValues();  // descending

  Similarity out;
  // Rank of Sigma_xy: 3 for a general point cloud, 2 for coplanar points (a flat drive), 1 or 0 for
  // collinear or coincident points, where Umeyama's rotation is no longer unique.
  const double tol = 1e-10 * std::max(D(0), 1e-300);
  out.degenerate = x.cols() < 3 || D(1) <= tol;

  // Eq. (39) for full rank and (43) for rank m-1: S flips the last axis when a reflection would fit
  // better than a rotation. (43) tests det(U)det(V) rather than det(Sigma_xy), which is 0 at rank m-1;
  // for full rank the two tests agree, so (43) serves both.
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (U.determinant() * V.determinant() < 0.0) S(2, 2) = -1.0;

  // Eq. (40): R = U S V^T.
  out.R = U * S * V.transpose();
  // Eq. (42): c = tr(D S) / sigma_x^2.
  if (with_scale) {
    if (sigma2_x <= 0.0) {
      out.scale = 1.0;  // all estimate points coincide: no scale can be observed
      out.degenerate = true;
    } else {
      out.scale = D.dot(S.diagonal()) / sigma2_x;
    }
  }
  // Eq. (41): t = mu_y - c R mu_x.
  out.t = mu_y - out.scale * out.R * mu_x;
  return out;
}

Alignment align(const Poses& gt, const Poses& est, const AlignmentOptions& options) {
  Alignment a;
  a.options = options;
  if (options.mode == AlignMode::None || gt.empty()) return a;

  const std::size_t n = options.first_n == 0 ? gt.size() : std::min(options.first_n, gt.size());
  a.pairs_used = n;
  if (n == 1) {
    if (options.mode == AlignMode::Sim3) {
      throw InputError("--align sim3 needs at least two poses to estimate a scale" +
                       std::string(options.first_n == 1 ? " (--align-first 1 uses one)" : " (one pair in total)"));
    }
    // Origin alignment: T = G_0 E_0^-1 maps the first estimate pose exactly onto the first ground truth.
    const Eigen::Isometry3d T = gt.front() * est.front().inverse();
    a.transform.R = T.linear();
    a.transform.t = T.translation();
    return a;
  }
  Eigen::Matrix3Xd x(3, static_cast<Eigen::Index>(n));
  Eigen::Matrix3Xd y(3, static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    x.col(static_cast<Eigen::Index>(i)) = est[i].translation();
    y.col(static_cast<Eigen::Index>(i)) = gt[i].translation();
  }
  a.transform = umeyama(x, y, options.mode == AlignMode::Sim3);
  return a;
}

Poses apply_similarity(const Similarity& T, const Poses& poses) {
  Poses out;
  out.reserve(poses.size());
  for (const auto& p : poses) {
    Eigen::Isometry3d q = Eigen::Isometry3d::Identity();
    q.linear() = T.R * p.linear();
    q.translation() = T.scale * T.R * p.translation() + T.t;
    out.push_back(q);
  }
  return out;
}

}  // namespace liod::eval
