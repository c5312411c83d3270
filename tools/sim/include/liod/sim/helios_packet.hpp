#pragma once
// RS-Helios-5515 MSOP and DIFOP payloads (1248 bytes each), laid out per sensors/rs-helios.md
// §2 and §6. Multi-byte fields are big-endian and written byte by byte.

#include <array>
#include <cstdint>

#include "liod/sim/lidar_model.hpp"

namespace liod::sim {

constexpr std::size_t kPacketBytes = 1248;
using Payload = std::array<std::uint8_t, kPacketBytes>;

struct MsopHeader {
  std::uint32_t counter = 0;     // top/bottom board packet counters
  std::uint64_t time_us = 0;     // UTC microseconds of the first firing of block 0
  double temperature_c = 40.0;
};

/// `blocks` are the 12 data blocks in packet order.
void encode_msop(const MsopHeader& header, const std::array<const FiringResult*, 12>& blocks,
                 const std::array<bool, 12>& second_return, Payload& out);

struct DifopInfo {
  std::uint16_t rpm = 600;
  bool dual_return = false;
  std::uint64_t time_us = 0;
  std::uint8_t sync_status = 2;  // PTP ok
  const HeliosCalibration* calibration = nullptr;
  std::array<std::uint8_t, 6> serial{};
};

void encode_difop(const DifopInfo& info, Payload& out);

}  // namespace liod::sim
