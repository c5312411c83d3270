#include "liod/body_rocking.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace liod {

double rocking_rate(const std::deque<ImuSample>& samples, double to, const Eigen::Vector3d& up_body,
                    const BodyRockingParams& params) {
  const Eigen::Vector3d up = up_body.normalized();
  const double from = to - params.window_s;
  // Buckets of average_s back from `to`, so that the newest ends with the window.
  const auto buckets = static_cast<std::size_t>(std::floor(params.window_s / params.average_s));
  std::vector<Eigen::Vector3d> sums(buckets, Eigen::Vector3d::Zero());
  std::vector<int> counts(buckets, 0);
  const auto first = std::lower_bound(samples.begin(), samples.end(), from,
                                      [](const ImuSample& s, double t) { return s.time < t; });
  for (auto it = first; it != samples.end() && it->time <= to; ++it) {
    const auto back = static_cast<std::size_t>((to - it->time) / params.average_s);
    if (back >= buckets || !it->gyro.allFinite()) continue;
    sums[back] += it->gyro - up * up.dot(it->gyro);
    ++counts[back];
  }
  std::vector<Eigen::Vector3d> means;
  for (std::size_t b = 0; b < buckets; ++b) {
    if (counts[b] > 0) means.push_back(sums[b] / counts[b]);
  }
  if (static_cast<double>(means.size()) * params.average_s < params.min_span_s || means.size() < 2) return -1.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& m : means) mean += m;
  mean /= static_cast<double>(means.size());
  double squared = 0.0;
  for (const auto& m : means) squared += (m - mean).squaredNorm();
  return std::sqrt(squared / static_cast<double>(means.size()));
}

BodyMotion body_motion(const std::deque<ImuSample>& samples, double to, const Eigen::Vector3d& up_body,
                       const BodyRockingParams& params) {
  const double rate = rocking_rate(samples, to, up_body, params);
  if (rate < 0.0) return BodyMotion::kUnknown;
  // White noise of density d averaged over T has variance d^2 / T per axis; two axes count. Twice
  // that: over ten windows the noise alone exceeds it about once in two thousand (chi-square, 18
  // degrees of freedom), and a standstill wrongly vetoed costs more than a veto missed.
  const double noise_variance = 2.0 * params.gyro_noise_density * params.gyro_noise_density / params.average_s;
  const double excess = params.rocking_rate_rad_s;
  return rate * rate > 2.0 * noise_variance + excess * excess ? BodyMotion::kRocking : BodyMotion::kStill;
}

}  // namespace liod
