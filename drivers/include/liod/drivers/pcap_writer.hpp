#pragma once
// Writes UDP datagrams as a classic pcap (nanosecond timestamps, Ethernet + IPv4 + UDP frames),
// the form PcapReader, Wireshark and tcpdump all read. Used by `liod record` and by tests.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "liod/drivers/c_file.hpp"
#include "liod/drivers/pcap_reader.hpp"

namespace liod::drivers {

class PcapWriter {
 public:
  /// Creates (truncates) the file and writes the file header; throws InputError on failure.
  explicit PcapWriter(const std::filesystem::path& path);
  ~PcapWriter();
  PcapWriter(const PcapWriter&) = delete;
  PcapWriter& operator=(const PcapWriter&) = delete;

  /// Appends one record: `d.payload` wrapped in Ethernet/IPv4/UDP headers built from `d`'s
  /// addresses and ports, stamped with `d.capture_time_ns`. Throws InputError on a write error
  /// or a payload too large for one IPv4 datagram.
  void write(const UdpDatagram& d);
  void flush();

 private:
  std::string path_;
  CFile file_;
  std::vector<std::uint8_t> frame_;
};

/// Builds the Ethernet + IPv4 + UDP frame PcapWriter stores (exposed for tests that re-wrap it).
void build_udp_frame(const UdpDatagram& d, std::vector<std::uint8_t>& frame);

}  // namespace liod::drivers
