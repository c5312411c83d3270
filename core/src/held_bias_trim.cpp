#include "liod/held_bias_trim.hpp"

#include <algorithm>

namespace liod {

std::optional<double> HeldBiasTrim::add_held_scan(double forward_velocity_correction, double duration) {
  if (window_s_ <= 0.0 || !(duration > 0.0)) return std::nullopt;
  rates_.push_back(forward_velocity_correction / duration);
  held_s_ += duration;
  if (held_s_ < window_s_) return std::nullopt;
  const auto middle = rates_.begin() + static_cast<std::ptrdiff_t>(rates_.size() / 2);
  std::nth_element(rates_.begin(), middle, rates_.end());
  // The prediction lost speed at this rate (corrections > 0): the bias it subtracts is too large.
  const double change = -gain_ * *middle;
  reset();
  return change;
}

void HeldBiasTrim::reset() {
  rates_.clear();
  held_s_ = 0.0;
}

}  // namespace liod
