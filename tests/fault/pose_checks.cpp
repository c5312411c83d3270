#include "pose_checks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "liod/eval/alignment.hpp"
#include "liod/eval/association.hpp"
#include "liod/eval/metrics.hpp"

namespace liod::test {
namespace {

Eigen::Isometry3d to_isometry(const pose::PoseMessage& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = p.orientation.normalized().toRotationMatrix();
  t.translation() = p.position;
  return t;
}

/// The ground truth at time t (interpolated; held beyond its ends).
Eigen::Isometry3d truth_at(const eval::Trajectory& truth, double t) {
  const auto& s = truth.stamps;
  const auto it = std::lower_bound(s.begin(), s.end(), t);
  if (it == s.begin()) return truth.poses.front();
  if (it == s.end()) return truth.poses.back();
  const auto j = static_cast<std::size_t>(it - s.begin());
  return eval::interpolate(truth.poses[j - 1], truth.poses[j], (t - s[j - 1]) / (s[j] - s[j - 1]));
}

double degrees(double rad) { return rad * 180.0 / std::numbers::pi; }

}  // namespace

namespace {

Accuracy accuracy_of(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth, double from, double to,
                     double aligned_from, double aligned_to, bool ok_only) {
  eval::Trajectory est;
  est.name = "scan poses";
  for (const auto& p : poses) {
    if (p.type != pose::MessageType::ScanPose || p.time < aligned_from || p.time >= aligned_to) continue;
    if (ok_only && (p.flags & pose::kOk) == 0) continue;
    est.stamps.push_back(p.time);
    est.poses.push_back(to_isometry(p));
  }
  Accuracy acc;
  if (est.size() < 3) return acc;
  eval::AssociationOptions association;
  association.interpolation = eval::Interpolation::On;
  const auto pairs = eval::associate(truth, est, association);
  const auto alignment = eval::align(pairs.gt, pairs.est, eval::AlignmentOptions{});
  const auto ate = eval::compute_ate(pairs.gt, eval::apply_similarity(alignment.transform, pairs.est));
  double sum = 0.0;
  for (std::size_t i = 0; i < pairs.stamps.size(); ++i) {
    if (pairs.stamps[i] < from || pairs.stamps[i] >= to) continue;
    const double e = ate.translation_m[i];
    sum += e * e;
    acc.max_m = std::max(acc.max_m, e);
    ++acc.poses;
  }
  if (acc.poses > 0) acc.rmse_m = std::sqrt(sum / static_cast<double>(acc.poses));
  return acc;
}

}  // namespace

Accuracy scan_accuracy(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth, double from,
                       double to) {
  return accuracy_of(poses, truth, from, to, -1e300, 1e300, false);
}

Accuracy scan_accuracy_within(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth, double from,
                              double to, bool ok_only) {
  return accuracy_of(poses, truth, from, to, from, to, ok_only);
}

double position_error_after(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth, double from,
                            double to, double t) {
  eval::Trajectory est;
  const pose::PoseMessage* at = nullptr;
  for (const auto& p : poses) {
    if (p.type != pose::MessageType::ScanPose) continue;
    if (at == nullptr && p.time >= t) at = &p;
    if (p.time < from || p.time >= to) continue;
    est.stamps.push_back(p.time);
    est.poses.push_back(to_isometry(p));
  }
  if (at == nullptr || est.size() < 3) return std::numeric_limits<double>::infinity();
  eval::AssociationOptions association;
  association.interpolation = eval::Interpolation::On;
  const auto pairs = eval::associate(truth, est, association);
  const auto alignment = eval::align(pairs.gt, pairs.est, eval::AlignmentOptions{});
  const auto placed = eval::apply_similarity(alignment.transform, eval::Poses{to_isometry(*at)});
  return (placed.front().translation() - truth_at(truth, at->time).translation()).norm();
}

Jump largest_jump(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth, bool with_initializing,
                  double from) {
  Jump worst;
  for (std::size_t i = 1; i < poses.size(); ++i) {
    if (!with_initializing && ((poses[i - 1].flags | poses[i].flags) & pose::kInitializing) != 0) continue;
    if (poses[i - 1].time < from) continue;
    const Eigen::Isometry3d a = to_isometry(poses[i - 1]);
    const Eigen::Isometry3d b = to_isometry(poses[i]);
    const Eigen::Isometry3d ta = truth_at(truth, poses[i - 1].time);
    const Eigen::Isometry3d tb = truth_at(truth, poses[i].time);
    const double dp = std::abs((b.translation() - a.translation()).norm() - (tb.translation() - ta.translation()).norm());
    const double dr = std::abs(eval::rotation_angle(a.linear().transpose() * b.linear()) -
                               eval::rotation_angle(ta.linear().transpose() * tb.linear()));
    if (dp > worst.position_m) {
      worst.position_m = dp;
      worst.at = poses[i].time;
    }
    worst.rotation_deg = std::max(worst.rotation_deg, degrees(dr));
  }
  return worst;
}

double largest_attitude_drift_deg(const std::vector<pose::PoseMessage>& poses, const eval::Trajectory& truth) {
  std::optional<Eigen::Isometry3d> first;
  std::optional<Eigen::Isometry3d> first_truth;
  double worst = 0.0;
  for (const auto& p : poses) {
    if (p.type != pose::MessageType::ScanPose || (p.flags & pose::kInitializing) != 0) continue;
    const Eigen::Isometry3d estimate = to_isometry(p);
    const Eigen::Isometry3d true_pose = truth_at(truth, p.time);
    if (!first) {
      first = estimate;
      first_truth = true_pose;
    }
    const Eigen::Matrix3d turned = first->linear().transpose() * estimate.linear();
    const Eigen::Matrix3d truly_turned = first_truth->linear().transpose() * true_pose.linear();
    worst = std::max(worst, degrees(eval::rotation_angle(turned.transpose() * truly_turned)));
  }
  return worst;
}

FlagCount count_flag(const std::vector<pose::PoseMessage>& poses, pose::MessageType type, std::uint32_t flag,
                     double from, double to) {
  FlagCount c;
  for (const auto& p : poses) {
    if (p.type != type || p.time < from || p.time >= to) continue;
    ++c.poses;
    if ((p.flags & flag) != 0) ++c.flagged;
  }
  return c;
}

}  // namespace liod::test
