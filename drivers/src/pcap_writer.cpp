#include "liod/drivers/pcap_writer.hpp"

#include <cerrno>
#include <cstring>

#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/input_error.hpp"

namespace liod::drivers {
namespace {

constexpr std::size_t kEthernetHeader = 14;
constexpr std::size_t kIpv4Header = 20;
constexpr std::size_t kUdpHeader = 8;
constexpr std::size_t kMaxUdpPayload = 65535 - kIpv4Header - kUdpHeader;

std::uint16_t ipv4_header_checksum(const std::uint8_t* h) {
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i < kIpv4Header; i += 2) sum += load_be16(h + i);
  while (sum >> 16) sum = (sum & 0xFFFFu) + (sum >> 16);
  return static_cast<std::uint16_t>(~sum);
}

}  // namespace

void build_udp_frame(const UdpDatagram& d, std::vector<std::uint8_t>& frame) {
  const std::size_t payload = d.payload.size();
  frame.assign(kEthernetHeader + kIpv4Header + kUdpHeader + payload, 0);
  std::uint8_t* eth = frame.data();
  std::memset(eth, 0xFF, 6);                              // broadcast destination, as the sensor sends
  const std::uint8_t src_mac[6] = {0x02, 0, 0, 0, 0, 1};  // locally administered
  std::memcpy(eth + 6, src_mac, 6);
  store_be16(eth + 12, 0x0800);

  std::uint8_t* ip = eth + kEthernetHeader;
  ip[0] = 0x45;
  store_be16(ip + 2, static_cast<std::uint16_t>(kIpv4Header + kUdpHeader + payload));
  store_be16(ip + 6, 0x4000);  // don't fragment
  ip[8] = 64;
  ip[9] = 17;
  store_be32(ip + 12, d.src_ip);
  store_be32(ip + 16, d.dst_ip);
  store_be16(ip + 10, ipv4_header_checksum(ip));

  std::uint8_t* udp = ip + kIpv4Header;
  store_be16(udp, d.src_port);
  store_be16(udp + 2, d.dst_port);
  store_be16(udp + 4, static_cast<std::uint16_t>(kUdpHeader + payload));
  // UDP checksum 0 = "not computed", legal for IPv4.
  if (payload != 0) std::memcpy(udp + kUdpHeader, d.payload.data(), payload);
}

PcapWriter::PcapWriter(const std::filesystem::path& path) : path_(path.string()) {
  file_.reset(std::fopen(path_.c_str(), "wb"));
  if (!file_) throw InputError(path_, 0, std::string("cannot create capture file: ") + std::strerror(errno));
  std::uint8_t header[24] = {};
  store_le32(header, 0xA1B23C4D);  // nanosecond-resolution pcap, little-endian
  store_le16(header + 4, 2);
  store_le16(header + 6, 4);
  store_le32(header + 16, 262144);  // snaplen
  store_le32(header + 20, 1);       // Ethernet
  if (std::fwrite(header, 1, sizeof header, file_.get()) != sizeof header)
    throw InputError(path_, 0, "cannot write pcap header");
}

PcapWriter::~PcapWriter() = default;

void PcapWriter::write(const UdpDatagram& d) {
  if (d.payload.size() > kMaxUdpPayload)
    throw InputError(path_, 0, "UDP payload of " + std::to_string(d.payload.size()) + " bytes is too large");
  build_udp_frame(d, frame_);
  std::uint8_t record[16];
  const std::int64_t t = d.capture_time_ns < 0 ? 0 : d.capture_time_ns;
  store_le32(record, static_cast<std::uint32_t>(t / 1'000'000'000));
  store_le32(record + 4, static_cast<std::uint32_t>(t % 1'000'000'000));
  store_le32(record + 8, static_cast<std::uint32_t>(frame_.size()));
  store_le32(record + 12, static_cast<std::uint32_t>(frame_.size()));
  if (std::fwrite(record, 1, sizeof record, file_.get()) != sizeof record ||
      std::fwrite(frame_.data(), 1, frame_.size(), file_.get()) != frame_.size())
    throw InputError(path_, 0, std::string("write failed: ") + std::strerror(errno));
}

void PcapWriter::flush() {
  if (std::fflush(file_.get()) != 0) throw InputError(path_, 0, std::string("flush failed: ") + std::strerror(errno));
}

}  // namespace liod::drivers
