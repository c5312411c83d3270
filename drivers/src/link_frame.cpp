#include "link_frame.hpp"

#include "liod/drivers/byte_order.hpp"

namespace liod::drivers::detail {
namespace {

constexpr std::uint16_t kEtherIpv4 = 0x0800;
constexpr std::uint16_t kEtherVlan = 0x8100;     // 802.1Q
constexpr std::uint16_t kEtherQinQ = 0x88A8;     // 802.1ad
constexpr std::uint16_t kEtherQinQOld = 0x9100;  // pre-standard double tagging
constexpr std::uint8_t kIpProtoUdp = 17;

FrameResult parse_ipv4(const std::uint8_t* p, std::size_t size, UdpDatagram& out) noexcept {
  if (size < 20) return FrameResult::Malformed;
  if ((p[0] >> 4) != 4) return FrameResult::NotIpv4;
  const std::size_t header_len = std::size_t{p[0] & 0x0Fu} * 4;
  const std::size_t total_len = load_be16(p + 2);
  if (header_len < 20 || total_len < header_len || total_len > size) return FrameResult::Malformed;
  const std::uint16_t flags_fragment = load_be16(p + 6);
  const bool more_fragments = (flags_fragment & 0x2000u) != 0;
  const bool nonzero_offset = (flags_fragment & 0x1FFFu) != 0;
  if (more_fragments || nonzero_offset) return FrameResult::Fragment;
  if (p[9] != kIpProtoUdp) return FrameResult::NotUdp;

  const std::uint8_t* udp = p + header_len;
  const std::size_t udp_avail = total_len - header_len;
  if (udp_avail < 8) return FrameResult::Malformed;
  const std::size_t udp_len = load_be16(udp + 4);
  if (udp_len < 8 || udp_len > udp_avail) return FrameResult::Malformed;

  out.src_ip = load_be32(p + 12);
  out.dst_ip = load_be32(p + 16);
  out.src_port = load_be16(udp);
  out.dst_port = load_be16(udp + 2);
  out.payload = std::span<const std::uint8_t>(udp + 8, udp_len - 8);
  return FrameResult::Udp;
}

FrameResult parse_by_ethertype(std::uint16_t ethertype, const std::uint8_t* p, std::size_t size,
                               UdpDatagram& out) noexcept {
  return ethertype == kEtherIpv4 ? parse_ipv4(p, size, out) : FrameResult::NotIpv4;
}

FrameResult parse_ethernet(const std::uint8_t* p, std::size_t size, UdpDatagram& out) noexcept {
  if (size < 14) return FrameResult::Malformed;
  std::size_t offset = 12;
  std::uint16_t ethertype = load_be16(p + offset);
  // Any stack of VLAN tags (4 bytes each: TPID already read, then TCI, then the inner type).
  while (ethertype == kEtherVlan || ethertype == kEtherQinQ || ethertype == kEtherQinQOld) {
    offset += 4;
    if (size < offset + 2) return FrameResult::Malformed;
    ethertype = load_be16(p + offset);
  }
  offset += 2;
  return parse_by_ethertype(ethertype, p + offset, size - offset, out);
}

FrameResult parse_raw_ip(const std::uint8_t* p, std::size_t size, UdpDatagram& out) noexcept {
  if (size < 1) return FrameResult::Malformed;
  return parse_ipv4(p, size, out);  // parse_ipv4 reports IPv6 (version 6) as NotIpv4
}

}  // namespace

bool is_supported_link_type(std::uint32_t link_type) noexcept {
  switch (link_type) {
    case kLinkEthernet:
    case kLinkRawBsd12:
    case kLinkRawBsd14:
    case kLinkRaw:
    case kLinkLinuxSll:
    case kLinkIpv4:
    case kLinkLinuxSll2:
      return true;
    default:
      return false;
  }
}

FrameResult parse_frame(std::uint32_t link_type, const std::uint8_t* frame, std::size_t size,
                        UdpDatagram& out) noexcept {
  switch (link_type) {
    case kLinkEthernet:
      return parse_ethernet(frame, size, out);
    case kLinkRawBsd12:
    case kLinkRawBsd14:
    case kLinkRaw:
    case kLinkIpv4:
      return parse_raw_ip(frame, size, out);
    case kLinkLinuxSll:  // 16-byte header, protocol (ethertype) at offset 14
      if (size < 16) return FrameResult::Malformed;
      return parse_by_ethertype(load_be16(frame + 14), frame + 16, size - 16, out);
    case kLinkLinuxSll2:  // 20-byte header, protocol (ethertype) at offset 0
      if (size < 20) return FrameResult::Malformed;
      return parse_by_ethertype(load_be16(frame), frame + 20, size - 20, out);
    default:
      return FrameResult::UnsupportedLink;
  }
}

}  // namespace liod::drivers::detail
