#pragma once
// A minimal, independent pcap + RS-Helios reader for the simulator's tests, written from the
// spec (sensors/rs-helios.md) alone so that the tests check the simulator against the spec and
// not against itself.

#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace liod::sim::test {

struct UdpRecord {
  std::uint64_t record_us = 0;
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
  std::array<std::uint8_t, 4> src_ip{};
  std::array<std::uint8_t, 4> dst_ip{};
  std::vector<std::uint8_t> payload;
};

inline std::uint32_t rd_le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8U |
         static_cast<std::uint32_t>(p[2]) << 16U | static_cast<std::uint32_t>(p[3]) << 24U;
}
inline std::uint16_t rd_be16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] << 8U | p[1]);
}
inline std::uint32_t rd_be32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) << 24U | static_cast<std::uint32_t>(p[1]) << 16U |
         static_cast<std::uint32_t>(p[2]) << 8U | p[3];
}

/// Reads a little-endian microsecond pcap of Ethernet/IPv4/UDP frames.
inline std::vector<UdpRecord> read_pcap(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw std::runtime_error("cannot open " + path);
  }
  std::vector<std::uint8_t> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (data.size() < 24 || rd_le32(data.data()) != 0xA1B2C3D4U || rd_le32(data.data() + 20) != 1U) {
    throw std::runtime_error("not a little-endian us Ethernet pcap: " + path);
  }
  std::vector<UdpRecord> out;
  std::size_t at = 24;
  while (at + 16 <= data.size()) {
    const std::uint8_t* h = data.data() + at;
    const std::uint32_t incl = rd_le32(h + 8);
    if (at + 16 + incl > data.size()) {
      throw std::runtime_error("truncated record");
    }
    const std::uint8_t* f = h + 16;
    UdpRecord r;
    r.record_us = static_cast<std::uint64_t>(rd_le32(h)) * 1000000U + rd_le32(h + 4);
    if (incl >= 42 && rd_be16(f + 12) == 0x0800 && f[14] == 0x45 && f[23] == 17) {
      std::copy(f + 26, f + 30, r.src_ip.begin());
      std::copy(f + 30, f + 34, r.dst_ip.begin());
      r.src_port = rd_be16(f + 34);
      r.dst_port = rd_be16(f + 36);
      const std::uint16_t udp_len = rd_be16(f + 38);
      r.payload.assign(f + 42, f + 42 + (udp_len - 8));
      out.push_back(std::move(r));
    }
    at += 16 + incl;
  }
  return out;
}

inline std::uint64_t header_time_us(const std::uint8_t* p) {
  std::uint64_t sec = 0;
  for (int i = 0; i < 6; ++i) {
    sec = sec << 8U | p[i];
  }
  return sec * 1000000U + rd_be32(p + 6);
}

struct DecodedPoint {
  double x = 0;
  double y = 0;
  double z = 0;
  double time_s = 0;  // LiDAR clock, absolute seconds
  int channel = 0;
  int intensity = 0;
  double range = 0;
};

/// Decodes one single- or dual-return Helios-32 MSOP packet per spec §3-§4 (RX lens offset,
/// measured firing table, per-channel azimuth interpolation).
inline void decode_msop(const std::vector<std::uint8_t>& p, const std::array<double, 32>& vert,
                        const std::array<double, 32>& horiz, std::vector<DecodedPoint>& out) {
  static constexpr std::array<double, 32> fire = {
      0.00,  1.57,  3.15,  4.72,  6.30,  7.87,  9.45,  11.36, 13.26, 15.17, 17.08,
      18.99, 20.56, 22.14, 23.71, 25.29, 26.53, 29.01, 27.77, 30.25, 31.49, 32.73,
      33.98, 35.22, 36.46, 37.70, 38.94, 40.18, 41.42, 42.67, 43.91, 45.15};
  const double kPi = 3.14159265358979323846;
  const double t0 = static_cast<double>(header_time_us(p.data() + 20)) * 1e-6;
  const bool dual = rd_be16(p.data() + 42 + 2) == rd_be16(p.data() + 142 + 2);
  const int step = dual ? 2 : 1;
  for (int b = 0; b < 12; ++b) {
    const std::uint8_t* blk = p.data() + 42 + 100 * b;
    if (blk[0] != 0xFF || blk[1] != 0xEE) {
      return;
    }
    const int az = rd_be16(blk + 2);
    int diff = 20;
    const int nb = (b / step + 1) * step;
    if (nb < 12) {
      diff = (rd_be16(p.data() + 42 + 100 * nb + 2) - az + 36000) % 36000;
      if (diff > 100) {
        diff = 20;
      }
    }
    const double tb = t0 + (b / step) * 55.56e-6;
    for (int c = 0; c < 32; ++c) {
      const int raw = rd_be16(blk + 4 + 3 * c);
      if (raw == 0) {
        continue;
      }
      const double d = raw * 0.0025;
      const double az_ch = az + diff * (fire[static_cast<std::size_t>(c)] / 55.56);
      const double az_f = az_ch + horiz[static_cast<std::size_t>(c)] * 100.0;
      const double el = vert[static_cast<std::size_t>(c)] * kPi / 180.0;
      const double a1 = az_f / 100.0 * kPi / 180.0;
      const double a0 = az_ch / 100.0 * kPi / 180.0;
      DecodedPoint q;
      q.x = d * std::cos(el) * std::cos(a1) + 0.03498 * std::cos(a0);
      q.y = -d * std::cos(el) * std::sin(a1) - 0.03498 * std::sin(a0);
      q.z = d * std::sin(el);
      q.time_s = tb + fire[static_cast<std::size_t>(c)] * 1e-6;
      q.channel = c;
      q.intensity = blk[4 + 3 * c + 2];
      q.range = d;
      out.push_back(q);
    }
  }
}

}  // namespace liod::sim::test
