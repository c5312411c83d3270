#pragma once
// Random numbers whose bytes do not depend on the standard library: std::mt19937_64 is fully
// specified by the standard, its distributions are not, so uniform and Gaussian draws are ours.

#include <cstdint>
#include <random>

namespace liod::sim {

/// Mixes a seed with a stream tag and an index into an independent 64-bit seed, so that every
/// consumer (world, trajectory, each LiDAR revolution, IMU) draws from its own sequence and the
/// output does not depend on the order or thread in which they run.
std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream, std::uint64_t index = 0);

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}

  /// Uniform in [0, 1) with 53 random bits.
  double uniform();
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [lo, hi] (inclusive).
  int uniform_int(int lo, int hi);
  bool bernoulli(double p) { return uniform() < p; }
  /// Standard normal by the Box-Muller transform.
  double gaussian();
  double gaussian(double sigma) { return sigma * gaussian(); }
  double exponential(double mean);
  /// +1 or -1 with equal probability.
  double sign() { return uniform() < 0.5 ? -1.0 : 1.0; }

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace liod::sim
