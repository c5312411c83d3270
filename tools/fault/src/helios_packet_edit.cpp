#include "liod/fault/helios_packet_edit.hpp"

#include <algorithm>
#include <cmath>

#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/rs_helios_difop.hpp"

namespace liod::fault {

using namespace drivers::helios;

bool is_msop(std::span<const std::uint8_t> payload) noexcept {
  return payload.size() == kPacketBytes && std::equal(kMsopMagic.begin(), kMsopMagic.end(), payload.begin());
}

std::int64_t msop_time_ns(std::span<const std::uint8_t> payload) noexcept {
  const auto seconds = static_cast<std::int64_t>(drivers::load_be48(payload.data() + kMsopTimeSeconds));
  const auto micros = static_cast<std::int64_t>(drivers::load_be32(payload.data() + kMsopTimeMicros));
  return seconds * 1'000'000'000 + micros * 1000;
}

void set_msop_time_ns(std::span<std::uint8_t> payload, std::int64_t time_ns) noexcept {
  const std::int64_t micros_total = time_ns / 1000;
  drivers::store_be48(payload.data() + kMsopTimeSeconds, static_cast<std::uint64_t>(micros_total / 1'000'000));
  drivers::store_be32(payload.data() + kMsopTimeMicros, static_cast<std::uint32_t>(micros_total % 1'000'000));
}

void set_msop_counters(std::span<std::uint8_t> payload, std::uint32_t counter) noexcept {
  drivers::store_be32(payload.data() + kMsopTopCounter, counter);
  drivers::store_be32(payload.data() + kMsopBottomCounter, counter);
}

double difop_vertical_deg(std::span<const std::uint8_t> difop, std::size_t laser) noexcept {
  return drivers::decode_calibration_angle(difop.data() + kDifopVerticalAngles + 3 * laser);
}

void set_difop_vertical_deg(std::span<std::uint8_t> difop, std::size_t laser, double degrees) noexcept {
  std::uint8_t* p = difop.data() + kDifopVerticalAngles + 3 * laser;
  p[0] = degrees < 0.0 ? 0x01 : 0x00;
  drivers::store_be16(p + 1, static_cast<std::uint16_t>(std::lround(std::abs(degrees) * 100.0)));
}

float metres_per_range_unit(std::span<const std::uint8_t> payload) noexcept {
  return payload[kMsopRangeResolutionByte] == 0 ? 0.005F : 0.0025F;
}

std::uint16_t SlotRef::range_units() const noexcept { return drivers::load_be16(bytes); }

void SlotRef::set_range_units(std::uint16_t units) noexcept { drivers::store_be16(bytes, units); }

std::optional<std::vector<double>> laser_elevations_deg(const Recording& recording) {
  drivers::HeliosDifop difop;
  for (const Packet& packet : recording.packets) {
    const std::span<const std::uint8_t> payload = packet.payload;
    if (!drivers::has_difop_magic(payload)) continue;
    if (drivers::parse_difop(payload, difop) != drivers::DifopStatus::Ok || !difop.angles_valid) continue;
    return std::vector<double>(difop.angles.vertical_deg.begin(), difop.angles.vertical_deg.end());
  }
  return std::nullopt;
}

}  // namespace liod::fault
