#pragma once
// Builders shared by the driver tests, the benchmark and the fuzz seed writer (fuzz/make_seeds.cpp):
// synthetic RS-Helios packets laid out per shared/sensors/rs-helios.md, and capture files of every
// flavour PcapReader accepts.

#include <array>
#include <cmath>
#include <iterator>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/pcap_writer.hpp"
#include "liod/drivers/rs_helios_model.hpp"
#include "scratch_dir.hpp"
#include "test_env.hpp"

namespace liod::drivers::test {

using liod::test::robosense_dir;
using liod::test::shared_dir;

struct SyntheticBlock {
  std::uint16_t azimuth = 0;
  std::array<std::uint16_t, 32> raw_distance{};
  std::array<std::uint8_t, 32> intensity{};
};

/// MSOP packet (spec §2): header time in whole µs, bottom-board counter, range flag, 12 blocks.
inline std::vector<std::uint8_t> make_msop(std::int64_t time_us, std::uint32_t counter,
                                           const std::array<SyntheticBlock, 12>& blocks,
                                           std::uint8_t range_flag = 1) {
  std::vector<std::uint8_t> p(helios::kPacketBytes, 0);
  std::memcpy(p.data(), helios::kMsopMagic.data(), 4);
  store_be16(p.data() + 4, 1);
  store_be32(p.data() + 8, counter);
  store_be32(p.data() + 12, counter);
  p[17] = range_flag;
  store_be48(p.data() + 20, static_cast<std::uint64_t>(time_us / 1'000'000));
  store_be32(p.data() + 26, static_cast<std::uint32_t>(time_us % 1'000'000));
  p[30] = 0x06;
  p[38] = 0xbc;
  p[39] = 0x1b;
  for (std::size_t k = 0; k < 12; ++k) {
    std::uint8_t* b = p.data() + 42 + k * 100;
    b[0] = 0xFF;
    b[1] = 0xEE;
    store_be16(b + 2, blocks[k].azimuth);
    for (std::size_t s = 0; s < 32; ++s) {
      store_be16(b + 4 + s * 3, blocks[k].raw_distance[s]);
      b[6 + s * 3] = blocks[k].intensity[s];
    }
  }
  p[1246] = 0x00;
  p[1247] = 0xFF;
  return p;
}

/// §6 3-byte angle: sign byte, BE magnitude in 0.01°.
inline void encode_angle(std::uint8_t* p, double deg) {
  const long units = std::lround(std::abs(deg) * 100.0);
  p[0] = deg < 0 ? 0x01 : 0x00;
  store_be16(p + 1, static_cast<std::uint16_t>(units));
}

/// DIFOP packet (spec §6) with the given angles (32 rows; missing rows are 0).
inline std::vector<std::uint8_t> make_difop(const std::vector<double>& vert, const std::vector<double>& horiz,
                                            std::uint8_t return_mode, std::uint16_t rpm = 600) {
  std::vector<std::uint8_t> p(helios::kPacketBytes, 0);
  std::memcpy(p.data(), helios::kDifopMagic.data(), 8);
  store_be16(p.data() + 8, rpm);
  store_be16(p.data() + 32, 0);
  store_be16(p.data() + 34, 36000);
  p[300] = return_mode;
  for (std::size_t ch = 0; ch < 32; ++ch) {
    encode_angle(p.data() + 468 + ch * 3, ch < vert.size() ? vert[ch] : 0.0);
    encode_angle(p.data() + 564 + ch * 3, ch < horiz.size() ? horiz[ch] : 0.0);
  }
  return p;
}

/// One captured record: time and the full link-layer frame.
struct Record {
  std::int64_t time_ns = 0;
  std::vector<std::uint8_t> frame;
  std::uint32_t orig_len = 0;  // 0 = frame.size()
};

inline std::vector<std::uint8_t> udp_ethernet_frame(std::uint16_t dst_port, const std::vector<std::uint8_t>& payload) {
  UdpDatagram d;
  d.src_ip = 0xC0A801C8;
  d.dst_ip = 0xC0A80166;
  d.src_port = dst_port;
  d.dst_port = dst_port;
  d.payload = payload;
  std::vector<std::uint8_t> frame;
  build_udp_frame(d, frame);
  return frame;
}

inline void put16(std::vector<std::uint8_t>& v, std::uint16_t x, bool be) {
  std::uint8_t b[2];
  if (be) store_be16(b, x); else store_le16(b, x);
  v.insert(v.end(), b, b + 2);
}
inline void put32(std::vector<std::uint8_t>& v, std::uint32_t x, bool be) {
  std::uint8_t b[4];
  if (be) store_be32(b, x); else store_le32(b, x);
  v.insert(v.end(), b, b + 4);
}

inline void write_bytes(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

inline std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Classic pcap bytes; `nanos` selects the ns magic, `be` big-endian fields.
inline std::vector<std::uint8_t> classic_pcap(const std::vector<Record>& records, std::uint32_t link_type,
                                              bool nanos = false, bool be = false) {
  std::vector<std::uint8_t> f;
  put32(f, nanos ? 0xA1B23C4D : 0xA1B2C3D4, be);
  put16(f, 2, be);
  put16(f, 4, be);
  put32(f, 0, be);
  put32(f, 0, be);
  put32(f, 65535, be);
  put32(f, link_type, be);
  for (const Record& r : records) {
    const std::int64_t frac = nanos ? r.time_ns % 1'000'000'000 : (r.time_ns % 1'000'000'000) / 1000;
    put32(f, static_cast<std::uint32_t>(r.time_ns / 1'000'000'000), be);
    put32(f, static_cast<std::uint32_t>(frac), be);
    put32(f, static_cast<std::uint32_t>(r.frame.size()), be);
    put32(f, r.orig_len != 0 ? r.orig_len : static_cast<std::uint32_t>(r.frame.size()), be);
    f.insert(f.end(), r.frame.begin(), r.frame.end());
  }
  return f;
}

/// pcapng bytes: SHB, one IDB (nanosecond if_tsresol), one EPB per record.
inline std::vector<std::uint8_t> pcapng(const std::vector<Record>& records, std::uint32_t link_type, bool be = false) {
  std::vector<std::uint8_t> f;
  // SHB: type, len 28, BOM, v1.0, section length -1
  put32(f, 0x0A0D0D0A, be);
  put32(f, 28, be);
  put32(f, 0x1A2B3C4D, be);
  put16(f, 1, be);
  put16(f, 0, be);
  put32(f, 0xFFFFFFFF, be);
  put32(f, 0xFFFFFFFF, be);
  put32(f, 28, be);
  // IDB with if_tsresol = 9 and opt_endofopt: 20 + 8 + 4 = 32 bytes
  put32(f, 1, be);
  put32(f, 32, be);
  put16(f, static_cast<std::uint16_t>(link_type), be);
  put16(f, 0, be);
  put32(f, 0, be);
  put16(f, 9, be);
  put16(f, 1, be);
  f.insert(f.end(), {9, 0, 0, 0});
  put32(f, 0, be);
  put32(f, 32, be);
  for (const Record& r : records) {
    const std::size_t padded = (r.frame.size() + 3) & ~std::size_t{3};
    const auto total = static_cast<std::uint32_t>(32 + padded);
    put32(f, 6, be);
    put32(f, total, be);
    put32(f, 0, be);
    const auto ts = static_cast<std::uint64_t>(r.time_ns);
    put32(f, static_cast<std::uint32_t>(ts >> 32), be);
    put32(f, static_cast<std::uint32_t>(ts), be);
    put32(f, static_cast<std::uint32_t>(r.frame.size()), be);
    put32(f, r.orig_len != 0 ? r.orig_len : static_cast<std::uint32_t>(r.frame.size()), be);
    f.insert(f.end(), r.frame.begin(), r.frame.end());
    f.insert(f.end(), padded - r.frame.size(), 0);
    put32(f, total, be);
  }
  return f;
}

/// A scratch directory of its own, removed by the destructor.
using TempDir = liod::test::ScratchDir;

}  // namespace liod::drivers::test
