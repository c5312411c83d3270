#pragma once
// What the faults need to know about RS-Helios-5515 MSOP packets, in one place, on top of
// liod_drivers' layout constants (rs_helios_model.hpp) and its DIFOP parser: where the header time
// sits, how a slot's range is scaled, and in-place edits of the returns. The reading side of each
// field is the decoder's (drivers/src/rs_helios_msop.cpp); the byte offsets below are the ones it
// reads (shared/sensors/rs-helios.md §2, §3).

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "liod/drivers/rs_helios_model.hpp"
#include "liod/fault/recording.hpp"

namespace liod::fault {

/// MSOP header fields a fault rewrites (spec §2, §3).
inline constexpr std::size_t kMsopRangeResolutionByte = 17;  // 1: 2.5 mm per unit, 0: 5 mm
inline constexpr std::size_t kMsopTimeSeconds = 20;          // 6 bytes, big-endian
inline constexpr std::size_t kMsopTimeMicros = 26;           // 4 bytes, big-endian
inline constexpr std::size_t kMsopTopCounter = 8;            // 4 bytes, big-endian (nebula)
inline constexpr std::size_t kMsopBottomCounter = 12;        // 4 bytes, big-endian, +1 per packet
/// DIFOP fields a fault rewrites (spec §6).
inline constexpr std::size_t kDifopMotorRpm = 8;             // 2 bytes, big-endian
inline constexpr std::size_t kDifopSyncStatus = 302;         // 0 invalid, 1 GPS, 2 PTP
inline constexpr std::size_t kDifopVerticalAngles = 468;     // 32 x 3 bytes

/// A 1248-byte payload with the MSOP magic.
[[nodiscard]] bool is_msop(std::span<const std::uint8_t> payload) noexcept;

/// Header time (first firing of block 0) in ns on the LiDAR clock.
[[nodiscard]] std::int64_t msop_time_ns(std::span<const std::uint8_t> payload) noexcept;
void set_msop_time_ns(std::span<std::uint8_t> payload, std::int64_t time_ns) noexcept;

/// Both packet counters of an MSOP header.
void set_msop_counters(std::span<std::uint8_t> payload, std::uint32_t counter) noexcept;
/// Calls `f(azimuth)` for the azimuth (0.01°) of every block with the FF EE flag and writes back
/// what it returns.
template <typename F>
void rewrite_block_azimuths(std::span<std::uint8_t> payload, F&& f);
/// A DIFOP's elevation of `laser` (degrees), in §6's sign-and-magnitude encoding.
[[nodiscard]] double difop_vertical_deg(std::span<const std::uint8_t> difop, std::size_t laser) noexcept;
void set_difop_vertical_deg(std::span<std::uint8_t> difop, std::size_t laser, double degrees) noexcept;

/// Metres per range unit, as the decoder reads byte 17 (anything but 0 means 2.5 mm).
[[nodiscard]] float metres_per_range_unit(std::span<const std::uint8_t> payload) noexcept;

/// One measurement slot of one firing block: its laser (channel) and its 3 bytes in the packet.
struct SlotRef {
  std::size_t laser = 0;  ///< 5515: the slot index, in single and dual return alike (§7)
  std::uint8_t* bytes = nullptr;
  [[nodiscard]] std::uint16_t range_units() const noexcept;
  void set_range_units(std::uint16_t units) noexcept;
  void set_intensity(std::uint8_t value) noexcept { bytes[2] = value; }
};

/// Calls `f(SlotRef)` for every slot of every block that carries the FF EE flag (as far as the
/// decoder would read: it stops at the first block without it).
template <typename F>
void for_each_slot(std::span<std::uint8_t> payload, F&& f) {
  using namespace drivers::helios;
  for (std::size_t b = 0; b < kBlocksPerPacket; ++b) {
    std::uint8_t* block = payload.data() + kHeaderBytes + b * kBlockBytes;
    if (block[0] != 0xFF || block[1] != 0xEE) return;
    for (std::size_t s = 0; s < kSlotsPerBlock; ++s) f(SlotRef{s, block + 4 + s * kSlotBytes});
  }
}

template <typename F>
void rewrite_block_azimuths(std::span<std::uint8_t> payload, F&& f) {
  using namespace drivers::helios;
  for (std::size_t b = 0; b < kBlocksPerPacket; ++b) {
    std::uint8_t* block = payload.data() + kHeaderBytes + b * kBlockBytes;
    if (block[0] != 0xFF || block[1] != 0xEE) return;
    const auto azimuth = static_cast<std::uint16_t>((block[2] << 8) | block[3]);
    const std::uint16_t out = f(azimuth);
    block[2] = static_cast<std::uint8_t>(out >> 8);
    block[3] = static_cast<std::uint8_t>(out);
  }
}

/// Elevation (degrees, + up) of each laser, from the first DIFOP whose angle table passes the
/// decoder's checks; nullopt when the recording has none.
[[nodiscard]] std::optional<std::vector<double>> laser_elevations_deg(const Recording& recording);

}  // namespace liod::fault
