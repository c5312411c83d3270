#pragma once
// Link-layer + IPv4 + UDP parsing of one captured frame (internal to liod_drivers).

#include <cstddef>
#include <cstdint>

#include "liod/drivers/pcap_reader.hpp"

namespace liod::drivers::detail {

// Link types as stored in pcap/pcapng files (LINKTYPE_*, tcpdump.org/linktypes.html).
inline constexpr std::uint32_t kLinkEthernet = 1;
inline constexpr std::uint32_t kLinkRawBsd12 = 12;  // DLT_RAW on most BSDs, seen in old files
inline constexpr std::uint32_t kLinkRawBsd14 = 14;  // DLT_RAW on OpenBSD
inline constexpr std::uint32_t kLinkRaw = 101;
inline constexpr std::uint32_t kLinkLinuxSll = 113;
inline constexpr std::uint32_t kLinkIpv4 = 228;
inline constexpr std::uint32_t kLinkLinuxSll2 = 276;

[[nodiscard]] bool is_supported_link_type(std::uint32_t link_type) noexcept;

enum class FrameResult : std::uint8_t { Udp, NotIpv4, NotUdp, Fragment, Malformed, UnsupportedLink };

/// Parses a frame of `link_type`; on Udp fills addresses, ports and payload of `out` (payload
/// points into `frame`). Trailing bytes after the IP datagram (Ethernet padding, FCS) are ignored.
/// Checksums are not verified: captures taken on the sending host carry offloaded (blank) ones.
[[nodiscard]] FrameResult parse_frame(std::uint32_t link_type, const std::uint8_t* frame, std::size_t size,
                                      UdpDatagram& out) noexcept;

}  // namespace liod::drivers::detail
