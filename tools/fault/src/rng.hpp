#pragma once
// The faults' random choices: SplitMix64, written out so that a seed gives the same faults with
// any standard library (std::uniform_*_distribution is implementation-defined).

#include <cstdint>

namespace liod::fault {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() noexcept {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  double uniform() noexcept { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// True with probability percent / 100.
  bool chance(double percent) noexcept { return uniform() * 100.0 < percent; }
  /// Uniform integer in [1, n].
  int one_to(int n) noexcept { return 1 + static_cast<int>(next() % static_cast<std::uint64_t>(n)); }

 private:
  std::uint64_t state_;
};

}  // namespace liod::fault
