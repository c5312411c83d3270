#include "liod/fault/apply_fault.hpp"

#include <variant>

#include "faults.hpp"

namespace liod::fault {

std::string apply_fault(const Fault& fault, Recording& recording, std::uint64_t seed) {
  Rng rng(seed);
  return std::visit([&](const auto& f) { return apply(f, recording, rng); }, fault);
}

}  // namespace liod::fault
