// What the MSOP packets carry: corrupted returns, or only the ground.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "faults.hpp"
#include "liod/angles.hpp"
#include "liod/fault/helios_packet_edit.hpp"

namespace liod::fault {

std::string apply(const CorruptPoints& f, Recording& r, Rng& rng) {
  std::size_t candidates = 0;
  std::size_t corrupted = 0;
  for (Packet& p : r.packets) {
    if (!is_msop(p.payload) || !f.window.contains(r.seconds_of(p.capture_time_ns))) continue;
    ++candidates;
    if (!rng.chance(f.percent)) continue;
    ++corrupted;
    for_each_slot(p.payload, [&](SlotRef slot) {
      switch (f.mode) {
        case Corruption::ZeroRange: slot.set_range_units(0); break;
        case Corruption::MaxRange: slot.set_range_units(0xFFFF); break;
        case Corruption::Garbage: {
          const std::uint64_t bits = rng.next();
          slot.set_range_units(static_cast<std::uint16_t>(bits));
          slot.set_intensity(static_cast<std::uint8_t>(bits >> 16));
          break;
        }
      }
    });
  }
  static constexpr const char* kModes[] = {"zero range", "max range", "garbage range/intensity"};
  return "corrupt: " + std::to_string(corrupted) + " of " + std::to_string(candidates) + " MSOP packets carry " +
         kModes[static_cast<int>(f.mode)] + " in every slot";
}

std::string apply(const GroundOnly& f, Recording& r, Rng&) {
  const auto elevations = laser_elevations_deg(r);
  if (!elevations) throw std::invalid_argument("ground-only: the recording has no DIFOP with a valid angle table");
  std::vector<double> sin_el;
  for (const double deg : *elevations) sin_el.push_back(std::sin(deg * kDegToRad));
  std::size_t returns = 0;
  std::size_t blanked = 0;
  for (Packet& p : r.packets) {
    if (!is_msop(p.payload) || !f.window.contains(r.seconds_of(p.capture_time_ns))) continue;
    const double metres = metres_per_range_unit(p.payload);
    for_each_slot(p.payload, [&](SlotRef slot) {
      const std::uint16_t units = slot.range_units();
      if (units == 0) return;
      ++returns;
      // The decoder's height of the return: z = range * sin(elevation) (spec §4).
      const double range = units * metres;
      if (range * sin_el[slot.laser] > f.max_z_m || range > f.max_range_m) {
        slot.set_range_units(0);
        ++blanked;
      }
    });
  }
  return "ground-only: " + std::to_string(blanked) + " of " + std::to_string(returns) + " returns above z = " +
         std::to_string(f.max_z_m) + " m or beyond " + std::to_string(f.max_range_m) + " m blanked";
}

}  // namespace liod::fault
