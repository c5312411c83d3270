#pragma once
// Reads UDP/IPv4 datagrams out of capture files: classic pcap (either byte order, µs or ns
// timestamps) and pcapng, over Ethernet (with 802.1Q / 802.1ad tags), Linux cooked SLL / SLL2 and
// raw IPv4 links. Hand-written rather than libpcap so that a file cut mid-record still yields
// every good record before the cut plus a counted, reported truncation, and so that files of any
// size stream through one reused buffer.
//
// Records that are not usable UDP/IPv4 datagrams are skipped and counted per reason (PcapStats);
// a file that is not a capture at all throws InputError from the constructor.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace liod::drivers {

struct UdpDatagram {
  /// Capture (record) time, nanoseconds since the Unix epoch as the file states it.
  std::int64_t capture_time_ns = 0;
  /// Addresses in host order (192.168.1.200 == 0xC0A801C8).
  std::uint32_t src_ip = 0;
  std::uint32_t dst_ip = 0;
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
  /// The UDP payload; points into the reader's buffer and is valid until the next next() call.
  std::span<const std::uint8_t> payload;
};

/// Counts of records read and of records skipped, one counter per reason.
struct PcapStats {
  std::uint64_t records = 0;           ///< records (packet blocks) read from the file
  std::uint64_t delivered = 0;         ///< UDP datagrams handed out by next()
  std::uint64_t port_filtered = 0;     ///< UDP datagrams whose destination port was not wanted
  std::uint64_t truncated_record = 0;  ///< captured length < original length (snaplen cut)
  std::uint64_t truncated_file = 0;    ///< 1 when the file ends inside a record or block
  std::uint64_t ip_fragment = 0;       ///< IPv4 fragments (MF set or offset != 0): not reassembled
  std::uint64_t not_ipv4 = 0;          ///< ARP, IPv6, other ethertypes
  std::uint64_t not_udp = 0;           ///< IPv4 but not UDP
  std::uint64_t malformed = 0;         ///< header lengths inconsistent with the captured bytes
  std::uint64_t unsupported_link = 0;  ///< link type this reader does not parse

  /// Records read but not delivered, excluding the port filter (which is a choice, not a fault).
  [[nodiscard]] std::uint64_t dropped() const noexcept {
    return truncated_record + ip_fragment + not_ipv4 + not_udp + malformed + unsupported_link;
  }
};

enum class CaptureFormat : std::uint8_t { Pcap, PcapNg };

class PcapReader {
 public:
  /// Opens and checks the file header. Throws InputError (naming the file) when it cannot be
  /// opened or is neither pcap nor pcapng, or a classic pcap uses an unsupported link type.
  explicit PcapReader(const std::filesystem::path& path);
  ~PcapReader();
  PcapReader(const PcapReader&) = delete;
  PcapReader& operator=(const PcapReader&) = delete;
  PcapReader(PcapReader&&) noexcept;
  PcapReader& operator=(PcapReader&&) noexcept;

  /// Only datagrams to these UDP destination ports are delivered; empty (default) = all ports.
  void set_port_filter(std::vector<std::uint16_t> ports);

  /// Next UDP datagram; false at the end of the file or when the file is cut or corrupt (then
  /// error() says where). Never throws for bad records.
  bool next(UdpDatagram& out);

  [[nodiscard]] const PcapStats& stats() const noexcept;
  /// Empty while the file reads cleanly; otherwise why reading stopped early (file, offset, why).
  [[nodiscard]] const std::string& error() const noexcept;
  [[nodiscard]] CaptureFormat format() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace liod::drivers
