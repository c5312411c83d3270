#pragma once
// Sends a pcap's UDP payloads to 127.0.0.1 (only) at a multiple of the recorded pace.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <thread>

#include "liod/drivers/pcap_reader.hpp"

namespace liod::test {

/// Returns the number of datagrams sent. `port_map` maps the recorded destination port to the
/// loopback port to use (others are not sent).
inline std::size_t send_pcap_loopback(const std::string& pcap, const std::map<std::uint16_t, std::uint16_t>& port_map,
                                      double pace) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return 0;
  drivers::PcapReader reader(pcap);
  drivers::UdpDatagram d;
  std::size_t sent = 0;
  std::int64_t first = -1;
  const auto start = std::chrono::steady_clock::now();
  while (reader.next(d)) {
    const auto it = port_map.find(d.dst_port);
    if (it == port_map.end()) continue;
    if (first < 0) first = d.capture_time_ns;
    const auto due = start + std::chrono::nanoseconds(static_cast<std::int64_t>(static_cast<double>(d.capture_time_ns - first) / pace));
    // Sleep coarsely, then spin the last 200 µs: the sensor's 0.55 ms packet spacing matters.
    while (std::chrono::steady_clock::now() + std::chrono::microseconds(200) < due) std::this_thread::sleep_for(std::chrono::microseconds(100));
    while (std::chrono::steady_clock::now() < due) {
    }
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(it->second);
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::sendto(fd, d.payload.data(), d.payload.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to) ==
        static_cast<ssize_t>(d.payload.size())) {
      ++sent;
    }
  }
  ::close(fd);
  return sent;
}

}  // namespace liod::test
