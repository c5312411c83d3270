#include "liod/calibration/time_offset.hpp"

#include <algorithm>
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

std::vector<double> gyro_norms_at(const std::vector<const LidarRate*>& used, const GyroIntegral& gyro, double shift) {
  std::vector<double> norms(used.size());
  for (std::size_t k = 0; k < used.size(); ++k) norms[k] = gyro.mean(used[k]->begin + shift, used[k]->end + shift).norm();
  return norms;
}

// y = a + b x + e at the found shift; d(b x_k)/d shift from the neighbouring shifts.
double shift_standard_error(const std::vector<double>& y, const std::vector<double>& x, const std::vector<double>& x_before,
                            const std::vector<double>& x_after, double step) {
  const auto n = static_cast<double>(y.size());
  double mx = 0.0, my = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) mx += x[k] / n, my += y[k] / n;
  double sxy = 0.0, sxx = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) sxy += (x[k] - mx) * (y[k] - my), sxx += (x[k] - mx) * (x[k] - mx);
  if (!(sxx > 0.0)) return 0.0;
  const double b = sxy / sxx;
  std::vector<double> e(y.size());
  std::vector<double> d(y.size());
  double mean_d = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) {
    e[k] = y[k] - my - b * (x[k] - mx);
    d[k] = b * (x_after[k] - x_before[k]) / (2.0 * step);
    mean_d += d[k] / n;
  }
  double see = 0.0, lagged = 0.0, sdd = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) {
    see += e[k] * e[k];
    if (k > 0) lagged += e[k] * e[k - 1];
    sdd += (d[k] - mean_d) * (d[k] - mean_d);
  }
  if (!(sdd > 0.0) || !(see > 0.0)) return 0.0;
  const double rho = std::clamp(lagged / see, 0.0, 0.99);
  const double variance = see / (n - 2.0) / sdd * (1.0 + rho) / (1.0 - rho);
  return std::sqrt(variance);
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
  for (int i = -steps; i <= steps; ++i) scores.push_back(correlation_of(lidar_norms, gyro_norms_at(used, gyro, i * config.step_s)));
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
  const double best_shift = (static_cast<double>(best) - steps) * config.step_s;
  result.shift_std_s = shift_standard_error(lidar_norms, gyro_norms_at(used, gyro, best_shift),
                                            gyro_norms_at(used, gyro, best_shift - config.step_s),
                                            gyro_norms_at(used, gyro, best_shift + config.step_s), config.step_s);
  return result;
}

}  // namespace liod::calibration
