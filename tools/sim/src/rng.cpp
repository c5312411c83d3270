#include "liod/sim/rng.hpp"

#include <cmath>
#include <numbers>

namespace liod::sim {

namespace {
std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27U)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31U);
}
}  // namespace

std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  return splitmix64(splitmix64(splitmix64(seed) ^ stream) + index);
}

double Rng::uniform() {
  return static_cast<double>(engine_() >> 11U) * 0x1.0p-53;
}

int Rng::uniform_int(int lo, int hi) {
  const auto span = static_cast<std::uint64_t>(static_cast<std::int64_t>(hi) - lo + 1);
  // The modulo bias is below 2^-40 for any span used here.
  return lo + static_cast<int>(engine_() % span);
}

double Rng::gaussian() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  double u1 = uniform();
  while (u1 <= 0.0) {
    u1 = uniform();
  }
  const double u2 = uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double a = 2.0 * std::numbers::pi * u2;
  spare_ = r * std::sin(a);
  has_spare_ = true;
  return r * std::cos(a);
}

double Rng::exponential(double mean) {
  double u = uniform();
  while (u <= 0.0) {
    u = uniform();
  }
  return -mean * std::log(u);
}

}  // namespace liod::sim
