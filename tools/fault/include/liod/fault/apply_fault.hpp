#pragma once
// Applies one fault to a recording in memory.

#include <cstdint>
#include <string>

#include "liod/fault/fault_spec.hpp"
#include "liod/fault/recording.hpp"

namespace liod::fault {

/// Rewrites `recording` with `fault`. Random choices come from `seed` only: the same recording,
/// fault and seed give the same bytes. Returns one line saying what was changed. Throws
/// std::invalid_argument when the fault cannot apply (e.g. ground-only without a DIFOP angle table).
std::string apply_fault(const Fault& fault, Recording& recording, std::uint64_t seed);

}  // namespace liod::fault
