#include "liod/sim/helios_packet.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace liod::sim {

namespace {
void put_u16(Payload& p, std::size_t at, std::uint32_t v) {
  p[at] = static_cast<std::uint8_t>((v >> 8U) & 0xFFU);
  p[at + 1] = static_cast<std::uint8_t>(v & 0xFFU);
}

void put_u32(Payload& p, std::size_t at, std::uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i) {
    p[at + i] = static_cast<std::uint8_t>((v >> (24U - 8U * i)) & 0xFFU);
  }
}

/// 6-byte seconds then 4-byte microseconds, both big-endian.
void put_time(Payload& p, std::size_t at, std::uint64_t time_us) {
  const std::uint64_t sec = time_us / 1000000U;
  const auto usec = static_cast<std::uint32_t>(time_us % 1000000U);
  for (std::size_t i = 0; i < 6; ++i) {
    p[at + i] = static_cast<std::uint8_t>((sec >> (40U - 8U * i)) & 0xFFU);
  }
  put_u32(p, at + 6, usec);
}

/// Sign byte then magnitude in 0.01 deg, big-endian.
void put_angle(Payload& p, std::size_t at, double deg) {
  const long v = std::lround(deg * 100.0);
  p[at] = v < 0 ? 0x01 : 0x00;
  put_u16(p, at + 1, static_cast<std::uint32_t>(std::abs(v)));
}
}  // namespace

void encode_msop(const MsopHeader& h, const std::array<const FiringResult*, 12>& blocks,
                 const std::array<bool, 12>& second_return, Payload& p) {
  p.fill(0);
  p[0] = 0x55;
  p[1] = 0xAA;
  p[2] = 0x05;
  p[3] = 0x5A;
  put_u16(p, 4, 0x0001);   // protocol version as sent by the real Helios unit
  put_u32(p, 8, h.counter);
  put_u32(p, 12, h.counter);
  p[17] = 0x01;            // range resolution: 2.5 mm
  put_u16(p, 18, 20);      // angle interval
  put_time(p, 20, h.time_us);
  p[30] = 0x06;            // lidar_type as the real unit sends it
  // Temperature: rs_driver's little-endian bit packing, 0.0625 degC per LSB.
  const long t = std::lround(std::abs(h.temperature_c) / 0.0625);
  p[38] = static_cast<std::uint8_t>((static_cast<unsigned long>(t) & 0x1FU) << 3U);
  p[39] = static_cast<std::uint8_t>(((static_cast<unsigned long>(t) >> 5U) & 0x7FU) |
                                    (h.temperature_c < 0 ? 0x80U : 0x00U));
  for (std::size_t b = 0; b < 12; ++b) {
    const std::size_t base = 42 + b * 100;
    p[base] = 0xFF;
    p[base + 1] = 0xEE;
    const FiringResult& f = *blocks[b];
    put_u16(p, base + 2, f.azimuth);
    const auto& ch = second_return[b] ? f.second : f.first;
    for (std::size_t c = 0; c < kChannels; ++c) {
      put_u16(p, base + 4 + 3 * c, ch[c].raw);
      p[base + 6 + 3 * c] = ch[c].intensity;
    }
  }
  p[1246] = 0x00;
  p[1247] = 0xFF;
}

void encode_difop(const DifopInfo& info, Payload& p) {
  p.fill(0);
  const std::uint8_t magic[8] = {0xA5, 0xFF, 0x00, 0x5A, 0x11, 0x11, 0x55, 0x55};
  std::copy(std::begin(magic), std::end(magic), p.begin());
  put_u16(p, 8, info.rpm);
  const std::uint8_t lidar_ip[4] = {192, 168, 1, 200};
  const std::uint8_t dest_ip[4] = {192, 168, 1, 102};
  const std::uint8_t mac[6] = {0x40, 0x2C, 0x76, 0x08, 0x4A, 0xCC};
  std::copy(std::begin(lidar_ip), std::end(lidar_ip), p.begin() + 10);
  std::copy(std::begin(dest_ip), std::end(dest_ip), p.begin() + 14);
  std::copy(std::begin(mac), std::end(mac), p.begin() + 18);
  put_u16(p, 24, 6699);
  put_u16(p, 28, 7788);
  put_u16(p, 32, 0);       // FOV start
  put_u16(p, 34, 36000);   // FOV end
  const std::uint8_t versions[23] = {0x01, 0x02, 0x03, 0x04, 0x05, 0x01, 0x02, 0x03,
                                     0x04, 0x05, 0x01, 0x02, 0x03, 0x04, 0x05, 0x01,
                                     0x02, 0x03, 0x04, 0x05, 0x01, 0x00, 0x00};
  std::copy(std::begin(versions), std::end(versions), p.begin() + 40);
  std::copy(info.serial.begin(), info.serial.end(), p.begin() + 292);
  p[300] = info.dual_return ? 0x00 : 0x04;
  p[301] = 0x01;  // PTP E2E
  p[302] = info.sync_status;
  put_time(p, 303, info.time_us);
  put_u16(p, 352, info.rpm);  // measured motor speed
  const char* gprmc = "$GPRMC,,V,,,,,,,,,,N*53";
  std::memcpy(p.data() + 382, gprmc, std::strlen(gprmc));
  if (info.calibration != nullptr) {
    for (std::size_t c = 0; c < kChannels; ++c) {
      put_angle(p, 468 + 3 * c, info.calibration->vertical_deg[c]);
      put_angle(p, 564 + 3 * c, info.calibration->horizontal_deg[c]);
    }
  }
  p[1246] = 0x0F;
  p[1247] = 0xF0;
}

}  // namespace liod::sim
