#include "liod/eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "liod/eval/io.hpp"

namespace liod::eval {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

}  // namespace

std::optional<Stats> summarize(std::vector<double> values) {
  if (values.empty()) return std::nullopt;
  Stats s;
  s.count = values.size();
  const auto n = static_cast<double>(values.size());
  double sum = 0.0;
  double sum_sq = 0.0;
  for (const double v : values) {
    sum += v;
    sum_sq += v * v;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  // Two-pass variance: sum_sq/n - mean^2 cancels catastrophically for errors that barely vary.
  double var = 0.0;
  for (const double v : values) var += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(var / n);
  std::sort(values.begin(), values.end());
  s.min = values.front();
  s.max = values.back();
  const std::size_t mid = values.size() / 2;
  s.median = values.size() % 2 == 1 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
  return s;
}

AteResult compute_ate(const Poses& gt, const Poses& est) {
  AteResult r;
  r.translation_m.reserve(gt.size());
  r.rotation_deg.reserve(gt.size());
  for (std::size_t i = 0; i < gt.size(); ++i) {
    r.translation_m.push_back((est[i].translation() - gt[i].translation()).norm());
    r.rotation_deg.push_back(rotation_angle(gt[i].linear().transpose() * est[i].linear()) * kDegPerRad);
  }
  if (auto s = summarize(r.translation_m)) r.translation = *s;
  if (auto s = summarize(r.rotation_deg)) r.rotation = *s;
  return r;
}

std::optional<AteSplit> compute_ate_split(const Poses& gt, const Poses& est, const Eigen::Vector3d& up) {
  const std::size_t n = gt.size();
  // The horizontal motion between each pair's neighbours, where there is enough of it.
  std::vector<std::optional<Eigen::Vector3d>> heading(n);
  bool any = false;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t before = i > 0 ? i - 1 : 0;
    const std::size_t after = std::min(i + 1, n - 1);
    Eigen::Vector3d motion = gt[after].translation() - gt[before].translation();
    motion -= motion.dot(up) * up;
    if (motion.norm() >= kMinTravelForHeading) {
      heading[i] = motion.normalized();
      any = true;
    }
  }
  if (!any) return std::nullopt;
  // A standstill keeps the heading it stopped with; the first poses, before any motion, take the first one.
  std::optional<Eigen::Vector3d> last;
  for (auto& h : heading) {
    if (h) {
      last = h;
    } else {
      h = last;
    }
  }
  std::optional<Eigen::Vector3d> next;
  for (std::size_t i = n; i-- > 0;) {
    if (heading[i]) {
      next = heading[i];
    } else {
      heading[i] = next;
    }
  }
  std::vector<double> along;
  std::vector<double> across;
  std::vector<double> vertical;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d error = est[i].translation() - gt[i].translation();
    along.push_back(error.dot(*heading[i]));
    across.push_back(error.dot(up.cross(*heading[i])));
    vertical.push_back(error.dot(up));
  }
  AteSplit r;
  r.up = up;
  r.along = *summarize(along);
  r.across = *summarize(across);
  r.vertical = *summarize(vertical);
  return r;
}

DeltaUnit parse_delta_unit(const std::string& text) {
  if (text == "m") return DeltaUnit::Metres;
  if (text == "s") return DeltaUnit::Seconds;
  if (text == "frames" || text == "f") return DeltaUnit::Frames;
  throw InputError("unknown delta unit '" + text + "' (want m, s or frames)");
}

const char* to_string(DeltaUnit unit) {
  switch (unit) {
    case DeltaUnit::Metres: return "m";
    case DeltaUnit::Seconds: return "s";
    case DeltaUnit::Frames: return "frames";
  }
  return "s";
}

std::vector<std::pair<std::size_t, std::size_t>> rpe_pairs(const std::vector<double>& stamps, const Poses& gt,
                                                            const RpeOptions& options) {
  std::vector<std::size_t> ids;
  const std::size_t n = gt.size();
  switch (options.unit) {
    case DeltaUnit::Frames: {
      const auto step = static_cast<std::size_t>(std::llround(options.delta));
      if (step == 0) throw InputError("--delta in frames must be at least 1");
      for (std::size_t i = 0; i < n; i += step) ids.push_back(i);
      break;
    }
    case DeltaUnit::Metres: {
      double path = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        if (i > 0) path += (gt[i].translation() - gt[i - 1].translation()).norm();
        if (path >= options.delta) {
          ids.push_back(i);
          path = 0.0;
        }
      }
      break;
    }
    case DeltaUnit::Seconds: {
      constexpr double kSlack = 1e-6;
      if (n > 0) ids.push_back(0);
      for (std::size_t i = 1; i < n; ++i) {
        if (stamps[i] - stamps[ids.back()] >= options.delta - kSlack) ids.push_back(i);
      }
      break;
    }
  }
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t k = 1; k < ids.size(); ++k) pairs.emplace_back(ids[k - 1], ids[k]);
  return pairs;
}

std::optional<RpeResult> compute_rpe(const std::vector<double>& stamps, const Poses& gt, const Poses& est,
                                     const RpeOptions& options) {
  if (!(options.delta > 0.0)) throw InputError("--delta must be positive");
  const auto pairs = rpe_pairs(stamps, gt, options);
  if (pairs.empty()) return std::nullopt;
  std::vector<double> trans;
  std::vector<double> rot;
  for (const auto& [i, j] : pairs) {
    const Eigen::Isometry3d E = (gt[i].inverse() * gt[j]).inverse() * (est[i].inverse() * est[j]);
    trans.push_back(E.translation().norm());
    rot.push_back(rotation_angle(E.linear()) * kDegPerRad);
  }
  RpeResult r;
  r.options = options;
  r.pairs = pairs.size();
  r.translation = *summarize(trans);
  r.rotation = *summarize(rot);
  return r;
}

std::optional<DistanceResult> compute_distance_travelled(const Poses& gt, const Poses& est, double step_m) {
  if (!(step_m > 0.0)) throw InputError("the distance step must be positive");
  const auto pairs = rpe_pairs({}, gt, {step_m, DeltaUnit::Metres});
  if (pairs.empty()) return std::nullopt;
  DistanceResult r;
  r.step_m = step_m;
  r.steps = pairs.size();
  for (const auto& [i, j] : pairs) {
    r.ground_truth_m += (gt[j].translation() - gt[i].translation()).norm();
    r.estimate_m += (est[j].translation() - est[i].translation()).norm();
  }
  r.error_pct = 100.0 * (r.estimate_m / r.ground_truth_m - 1.0);
  return r;
}

}  // namespace liod::eval
