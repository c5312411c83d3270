#pragma once
// RS-Helios models and the packet-layout constants shared by the MSOP and DIFOP parsers
// (shared/sensors/rs-helios.md §1, §2, §3).

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace liod::drivers {

enum class HeliosModel : std::uint8_t {
  Helios5515,  ///< RS-Helios-5515 ("C32"), 32 lasers
  Helios16P,   ///< RS-Helios-16P, 16 lasers in 32 slots (spec §8)
};

[[nodiscard]] constexpr std::uint16_t beam_count(HeliosModel m) noexcept {
  return m == HeliosModel::Helios16P ? 16 : 32;
}
[[nodiscard]] std::string_view to_string(HeliosModel m) noexcept;
/// Accepts "helios5515", "helios32", "c32", "helios16p" (any case); nullopt otherwise.
[[nodiscard]] std::optional<HeliosModel> parse_helios_model(std::string_view name) noexcept;

namespace helios {

inline constexpr std::size_t kPacketBytes = 1248;  // MSOP and DIFOP alike (§1)
inline constexpr std::uint16_t kDefaultMsopPort = 6699;
inline constexpr std::uint16_t kDefaultDifopPort = 7788;
inline constexpr std::array<std::uint8_t, 4> kMsopMagic = {0x55, 0xAA, 0x05, 0x5A};
inline constexpr std::array<std::uint8_t, 8> kDifopMagic = {0xA5, 0xFF, 0x00, 0x5A, 0x11, 0x11, 0x55, 0x55};

inline constexpr std::size_t kHeaderBytes = 42;  // §2
inline constexpr std::size_t kBlocksPerPacket = 12;
inline constexpr std::size_t kBlockBytes = 100;  // §2.1
inline constexpr std::size_t kSlotsPerBlock = 32;
inline constexpr std::size_t kSlotBytes = 3;  // §2.2
inline constexpr std::size_t kMaxPointsPerPacket = kBlocksPerPacket * kSlotsPerBlock;

inline constexpr std::uint16_t kAzimuthUnits = 36000;  // 0.01° per unit
inline constexpr std::int32_t kFullCircle = kAzimuthUnits;  // the same, as a signed count for azimuth arithmetic
/// Consecutive blocks further apart than this (1.00°) straddle the FOV blind zone (§3).
inline constexpr std::int32_t kBlindZoneJump = 100;

inline constexpr double kBlockPeriodS = 55.56e-6;  // §3
inline constexpr double kLensOffsetRxM = 0.03498;  // §4
inline constexpr double kDefaultRotationHz = 10.0;
/// The slowest rotation the RS-Helios runs at: 300 rpm (it turns at 300, 600 or 1200 rpm; §3
/// counts 3600 blocks per revolution at 5 Hz).
inline constexpr double kMinRotationHz = 5.0;
/// Firing blocks of one revolution at the slowest rotation, dual return (two blocks per firing on
/// the 5515, §7): 2 x 1 / (5 Hz x 55.56 us) = 7200. The 16P's blocks hold both returns (§8): fewer.
inline constexpr std::uint32_t kMaxBlocksPerRevolution =
    2 * static_cast<std::uint32_t>(1.0 / (kMinRotationHz * kBlockPeriodS) + 0.5);
/// A sweep longer than this many blocks is no revolution: the split azimuth was never crossed (a
/// stalled motor, a stuck azimuth field, a foreign sender). A quarter above one revolution at the
/// slowest rate, the margin for a motor running that much slow; 9000 blocks, at most 288 000 points.
inline constexpr std::uint32_t kMaxSweepBlocks = kMaxBlocksPerRevolution / 4 * 5;
static_assert(kMaxBlocksPerRevolution == 7200 && kMaxSweepBlocks == 9000);
/// The header's seconds field is 48 bits; beyond this (year 2255) nanoseconds overflow int64, so
/// a larger value can only be a corrupt packet.
inline constexpr std::uint64_t kMaxTimestampSeconds = 9'000'000'000ULL;

/// Per-slot firing offsets inside a block, µs: the measured table (§3.1, nebula). Slots 17 and 18
/// are out of order on purpose (the hardware fires them that way). We use it for both models:
/// it reproduces the real 16P recording's timing, and for the 5515 it differs from rs_driver's
/// uniform 1.73 µs steps by < 8 µs (< 0.03° of rotation).
inline constexpr std::array<float, 32> kFiringOffsetsUs = {
    0.00F,  1.57F,  3.15F,  4.72F,  6.30F,  7.87F,  9.45F,  11.36F, 13.26F, 15.17F, 17.08F,
    18.99F, 20.56F, 22.14F, 23.71F, 25.29F, 26.53F, 29.01F, 27.77F, 30.25F, 31.49F, 32.73F,
    33.98F, 35.22F, 36.46F, 37.70F, 38.94F, 40.18F, 41.42F, 42.67F, 43.91F, 45.15F};

/// DIFOP return-mode byte (§6).
inline constexpr std::uint8_t kReturnDual = 0x00;
inline constexpr std::uint8_t kReturnStrongest = 0x04;
inline constexpr std::uint8_t kReturnLast = 0x05;
inline constexpr std::uint8_t kReturnFirst = 0x06;

}  // namespace helios
}  // namespace liod::drivers
