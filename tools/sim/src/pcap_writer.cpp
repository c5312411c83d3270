#include "liod/sim/pcap_writer.hpp"

#include <stdexcept>
#include <vector>

namespace liod::sim {

namespace {
// pcap headers are little-endian here (the magic tells readers so); network headers big-endian.
void le32(std::vector<std::uint8_t>& v, std::uint32_t x) {
  for (int i = 0; i < 4; ++i) {
    v.push_back(static_cast<std::uint8_t>((x >> (8 * i)) & 0xFFU));
  }
}
void le16(std::vector<std::uint8_t>& v, std::uint16_t x) {
  v.push_back(static_cast<std::uint8_t>(x & 0xFFU));
  v.push_back(static_cast<std::uint8_t>(x >> 8U));
}
void be16(std::vector<std::uint8_t>& v, std::uint32_t x) {
  v.push_back(static_cast<std::uint8_t>((x >> 8U) & 0xFFU));
  v.push_back(static_cast<std::uint8_t>(x & 0xFFU));
}

std::uint16_t ip_checksum(const std::uint8_t* h, std::size_t n) {
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i + 1 < n; i += 2) {
    sum += static_cast<std::uint32_t>(h[i] << 8U | h[i + 1]);
  }
  while ((sum >> 16U) != 0) {
    sum = (sum & 0xFFFFU) + (sum >> 16U);
  }
  return static_cast<std::uint16_t>(~sum & 0xFFFFU);
}

constexpr std::uint8_t kSrcIp[4] = {192, 168, 1, 200};
constexpr std::uint8_t kDstIp[4] = {192, 168, 1, 102};
}  // namespace

PcapWriter::PcapWriter(const std::string& path) : out_(path, std::ios::binary), path_(path) {
  if (!out_) {
    throw std::runtime_error("cannot create '" + path + "'");
  }
  std::vector<std::uint8_t> h;
  le32(h, 0xA1B2C3D4U);
  le16(h, 2);
  le16(h, 4);
  le32(h, 0);
  le32(h, 0);
  le32(h, 65535);
  le32(h, 1);  // LINKTYPE_ETHERNET
  out_.write(reinterpret_cast<const char*>(h.data()), static_cast<std::streamsize>(h.size()));
}

void PcapWriter::write_udp(std::uint64_t time_us, std::uint16_t port,
                           std::span<const std::uint8_t> payload) {
  std::vector<std::uint8_t> f;
  f.reserve(42 + payload.size() + 16);
  const std::size_t frame_len = 42 + payload.size();
  le32(f, static_cast<std::uint32_t>(time_us / 1000000U));
  le32(f, static_cast<std::uint32_t>(time_us % 1000000U));
  le32(f, static_cast<std::uint32_t>(frame_len));
  le32(f, static_cast<std::uint32_t>(frame_len));
  // Ethernet: host NIC <- RoboSense MAC.
  const std::uint8_t dst_mac[6] = {0x00, 0x1B, 0x21, 0x3C, 0x9D, 0x02};
  const std::uint8_t src_mac[6] = {0x40, 0x2C, 0x76, 0x08, 0x4A, 0xCC};
  f.insert(f.end(), std::begin(dst_mac), std::end(dst_mac));
  f.insert(f.end(), std::begin(src_mac), std::end(src_mac));
  be16(f, 0x0800);
  const std::size_t ip_at = f.size();
  f.push_back(0x45);
  f.push_back(0x00);
  be16(f, static_cast<std::uint32_t>(20 + 8 + payload.size()));
  be16(f, ip_id_++);
  be16(f, 0x4000);  // don't fragment
  f.push_back(64);
  f.push_back(17);  // UDP
  be16(f, 0);
  f.insert(f.end(), std::begin(kSrcIp), std::end(kSrcIp));
  f.insert(f.end(), std::begin(kDstIp), std::end(kDstIp));
  const std::uint16_t csum = ip_checksum(f.data() + ip_at, 20);
  f[ip_at + 10] = static_cast<std::uint8_t>(csum >> 8U);
  f[ip_at + 11] = static_cast<std::uint8_t>(csum & 0xFFU);
  be16(f, port);  // the sensor sends from the port it sends to
  be16(f, port);
  be16(f, static_cast<std::uint32_t>(8 + payload.size()));
  be16(f, 0);  // no UDP checksum, as IPv4 allows
  f.insert(f.end(), payload.begin(), payload.end());
  out_.write(reinterpret_cast<const char*>(f.data()), static_cast<std::streamsize>(f.size()));
  if (!out_) {
    throw std::runtime_error("write failed on '" + path_ + "'");
  }
  ++records_;
}

}  // namespace liod::sim
