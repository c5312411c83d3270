#pragma once
// Classic pcap (LINKTYPE_ETHERNET, microsecond stamps) of UDP datagrams from the LiDAR at
// 192.168.1.200 to the host at 192.168.1.102, as a capture on the host's interface would look.

#include <cstdint>
#include <fstream>
#include <span>
#include <string>

namespace liod::sim {

class PcapWriter {
 public:
  /// Throws std::runtime_error when the file cannot be created.
  explicit PcapWriter(const std::string& path);

  void write_udp(std::uint64_t time_us, std::uint16_t port, std::span<const std::uint8_t> payload);
  std::uint64_t records() const { return records_; }

 private:
  std::ofstream out_;
  std::string path_;
  std::uint16_t ip_id_ = 0;
  std::uint64_t records_ = 0;
};

}  // namespace liod::sim
