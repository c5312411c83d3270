#pragma once
// A small client for liod's pose socket (docs/pose-protocol.md):
//
//   liod::PoseClient client("/run/liod/pose.sock");          // throws if it cannot connect
//   liod::pose::Message m;
//   while (client.read(m, std::chrono::milliseconds(500)))  // false on timeout or disconnect
//     if (m.type == liod::pose::MessageType::ScanPose) use(m.pose);

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "liod/daemon/pose_protocol.hpp"

namespace liod {

class PoseClient {
 public:
  /// Connects (binary mode, both rates). Throws std::runtime_error when it cannot.
  explicit PoseClient(const std::string& path);
  ~PoseClient();
  PoseClient(const PoseClient&) = delete;
  PoseClient& operator=(const PoseClient&) = delete;

  /// Sends a mode request line: "json", "binary", "scan" or "all".
  void request(const std::string& line);
  /// Next binary message; false on timeout, on disconnect (then connected() is false) or on a
  /// stream that is not liod v1 (disconnects).
  bool read(pose::Message& out, std::chrono::milliseconds timeout);
  /// Next text line (JSON mode), without the newline; false on timeout or disconnect.
  bool read_line(std::string& line, std::chrono::milliseconds timeout);
  bool connected() const { return fd_ >= 0; }
  int fd() const { return fd_; }

 private:
  bool fill(std::chrono::steady_clock::time_point deadline);
  void disconnect();
  int fd_ = -1;
  std::vector<std::uint8_t> buffer_;
  std::size_t start_ = 0;
};

}  // namespace liod
