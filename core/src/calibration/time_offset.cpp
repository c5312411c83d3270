#include "liod/calibration/time_offset.hpp"

#include <cmath>

namespace liod::calibration {
namespace {

/// Pearson correlation of two equally long series; 0 when either is constant.
double correlation_of(const std::vector<double>& x, const std::vector<double>& y) {
  const auto n = static_cast<double>(x.size());
  double mx = 0.0;
  double my = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= n;
  my /= n;
  double sxy = 0.0;
  double sxx = 0.0;
  double syy = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxx > 0.0 && syy > 0.0 ? sxy / std::sqrt(sxx * syy) : 0.0;
}

}  // namespace

TimeShift estimate_time_shift(const std::vector<LidarRate>& lidar, const GyroIntegral& gyro, const TimeOffsetConfig& config) {
  TimeShift result;
  // Only the intervals the gyro covers at every shift, so that each shift is scored on the same set.
  std::vector<const LidarRate*> used;
  std::vector<double> lidar_norms;
  for (const LidarRate& r : lidar) {
    if (gyro.covers(r.begin - config.search_s, r.end + config.search_s)) {
      used.push_back(&r);
      lidar_norms.push_back(r.rate.norm());
    }
  }
  result.intervals = used.size();
  const int steps = static_cast<int>(std::lround(config.search_s / config.step_s));
  if (used.size() < 10 || steps < 1) return result;

  std::vector<double> scores;
  std::vector<double> gyro_norms(used.size());
  for (int i = -steps; i <= steps; ++i) {
    const double shift = i * config.step_s;
    for (std::size_t k = 0; k < used.size(); ++k) {
      gyro_norms[k] = gyro.mean(used[k]->begin + shift, used[k]->end + shift).norm();
    }
    scores.push_back(correlation_of(lidar_norms, gyro_norms));
  }
  std::size_t best = 0;
  for (std::size_t i = 1; i < scores.size(); ++i) {
    if (scores[i] > scores[best]) best = i;
  }
  result.correlation = scores[best];
  if (best == 0 || best + 1 == scores.size()) return result;
  // The vertex of the parabola through the peak and its two neighbours.
  const double a = scores[best - 1];
  const double b = scores[best];
  const double c = scores[best + 1];
  const double denominator = a - 2.0 * b + c;
  const double vertex = denominator < 0.0 ? 0.5 * (a - c) / denominator : 0.0;
  result.shift_s = (static_cast<double>(best) - steps + vertex) * config.step_s;
  result.found = true;
  return result;
}

}  // namespace liod::calibration
