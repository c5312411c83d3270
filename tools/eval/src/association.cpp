#include "liod/eval/association.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "liod/eval/io.hpp"

namespace liod::eval {
namespace {

Association by_index(const Trajectory& gt, const Trajectory& est) {
  if (gt.size() != est.size()) {
    throw InputError("cannot pair by index: " + gt.name + " has " + std::to_string(gt.size()) + " poses, " +
                     est.name + " has " + std::to_string(est.size()) +
                     " (KITTI files pair line by line; give --gt-times/--est-times to pair by time)");
  }
  Association a;
  a.by_time = false;
  a.gt = gt.poses;
  a.est = est.poses;
  for (std::size_t i = 0; i < est.size(); ++i) {
    a.stamps.push_back(static_cast<double>(i));
    a.est_index.push_back(i);
  }
  return a;
}

Association nearest(const Trajectory& gt, const Trajectory& est, const AssociationOptions& o) {
  Association a;
  const auto& g = gt.stamps;
  std::size_t j = 0;
  std::size_t last_gt = 0;
  double last_diff = 0.0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const double t = est.stamps[i] + o.est_time_offset;
    // Both stamp lists increase, so the nearest ground-truth index never moves backwards.
    while (j + 1 < g.size() && std::abs(g[j + 1] - t) <= std::abs(g[j] - t)) ++j;
    const double diff = std::abs(g[j] - t);
    if (diff > o.max_dt) continue;
    if (!a.est.empty() && j == last_gt) {
      if (diff >= last_diff) continue;
      // A later estimate is closer to the same ground-truth pose: it takes the pair over.
      a.stamps.pop_back();
      a.gt.pop_back();
      a.est.pop_back();
      a.est_index.pop_back();
    }
    a.stamps.push_back(t);
    a.gt.push_back(gt.poses[j]);
    a.est.push_back(est.poses[i]);
    a.est_index.push_back(i);
    last_gt = j;
    last_diff = diff;
  }
  return a;
}

Association interpolated(const Trajectory& gt, const Trajectory& est, const AssociationOptions& o) {
  Association a;
  a.interpolated = true;
  const auto& g = gt.stamps;
  std::size_t j = 0;  // g[j] <= t < g[j+1] once found
  for (std::size_t i = 0; i < est.size(); ++i) {
    const double t = est.stamps[i] + o.est_time_offset;
    if (t < g.front() || t > g.back()) continue;
    while (j + 1 < g.size() && g[j + 1] <= t) ++j;
    Eigen::Isometry3d pose;
    if (g[j] == t) {
      pose = gt.poses[j];
    } else {
      const double gap = g[j + 1] - g[j];
      if (gap > o.max_gap) continue;
      pose = interpolate(gt.poses[j], gt.poses[j + 1], (t - g[j]) / gap);
    }
    a.stamps.push_back(t);
    a.gt.push_back(pose);
    a.est.push_back(est.poses[i]);
    a.est_index.push_back(i);
  }
  return a;
}

}  // namespace

Interpolation parse_interpolation(const std::string& text) {
  if (text == "auto") return Interpolation::Auto;
  if (text == "on") return Interpolation::On;
  if (text == "off") return Interpolation::Off;
  throw InputError("unknown interpolation mode '" + text + "' (want auto, on or off)");
}

double median_period(const std::vector<double>& stamps) {
  if (stamps.size() < 2) return 0.0;
  std::vector<double> d;
  d.reserve(stamps.size() - 1);
  for (std::size_t i = 1; i < stamps.size(); ++i) d.push_back(stamps[i] - stamps[i - 1]);
  const auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  return *mid;
}

Eigen::Isometry3d interpolate(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double u) {
  const Eigen::Quaterniond qa(a.linear());
  const Eigen::Quaterniond qb(b.linear());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = qa.slerp(u, qb).toRotationMatrix();  // Eigen's slerp takes the short way round
  out.translation() = (1.0 - u) * a.translation() + u * b.translation();
  return out;
}

Association associate(const Trajectory& gt, const Trajectory& est, const AssociationOptions& options) {
  if (gt.has_stamps() != est.has_stamps()) {
    throw InputError("one trajectory has timestamps and the other has none (" +
                     (gt.has_stamps() ? est.name : gt.name) +
                     "); give the KITTI file its times with --gt-times/--est-times");
  }
  if (!gt.has_stamps()) return by_index(gt, est);

  bool interpolate_gt = options.interpolation == Interpolation::On;
  if (options.interpolation == Interpolation::Auto) {
    interpolate_gt = gt.size() >= 2 && median_period(gt.stamps) < 0.75 * median_period(est.stamps);
  }
  Association a = interpolate_gt ? interpolated(gt, est, options) : nearest(gt, est, options);
  if (a.est.empty()) {
    std::ostringstream msg;
    msg.precision(17);
    msg << "no overlap in time between " << gt.name << " [" << gt.stamps.front() << ", " << gt.stamps.back()
        << "] and " << est.name << " [" << est.stamps.front() + options.est_time_offset << ", "
        << est.stamps.back() + options.est_time_offset << "]";
    if (interpolate_gt) {
      msg << " (interpolating ground truth across gaps up to --max-gap " << options.max_gap << " s)";
    } else {
      msg << " (nearest stamp within --max-dt " << options.max_dt << " s)";
    }
    throw InputError(msg.str());
  }
  return a;
}

}  // namespace liod::eval
