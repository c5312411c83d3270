#pragma once
// The points decoded from one LiDAR packet, grouped by firing block: what a packet decoder hands
// to the SweepAssembler. Fixed capacity so decoding never allocates.

#include <array>
#include <cstddef>
#include <cstdint>

#include "liod/types.hpp"

namespace liod::drivers {

struct FiringBlock {
  std::uint16_t azimuth = 0;  ///< block azimuth, 0.01° (0..35999), as in the packet
  float time_offset_s = 0.0F; ///< block time after PacketPoints::time_ns
  std::uint16_t first_point = 0;
  std::uint16_t point_count = 0;
};

struct PacketPoints {
  static constexpr std::size_t kMaxBlocks = 12;
  static constexpr std::size_t kMaxPoints = 384;

  std::int64_t time_ns = 0;  ///< packet time base (time of the first firing of block 0)
  std::size_t block_count = 0;
  std::size_t point_count = 0;
  std::array<FiringBlock, kMaxBlocks> blocks{};
  /// points[i].time is seconds after time_ns (not yet relative to a sweep).
  std::array<LidarPoint, kMaxPoints> points{};
};

}  // namespace liod::drivers
