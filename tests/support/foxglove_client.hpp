#pragma once
// A Foxglove WebSocket client (foxglove.websocket.v1) for the live view's tests and benchmark: it
// connects as Foxglove Studio does, reads serverInfo and advertise, subscribes, and then collects
// every message data frame on a thread of its own, decoded (channel topic, log time, JSON).
// The WebSocket under it (websocket_client.hpp) is written from RFC 6455 on POSIX sockets, not
// taken from Boost.Beast as the server's is: an independent implementation tests the server's
// handshake and framing better than Beast talking to Beast would, and the tests compile without
// Beast. Both are built once into liod_test_foxglove_client (tests/daemon/CMakeLists.txt).
#include <nlohmann/json.hpp>

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "websocket_client.hpp"

namespace liod::test {

struct FoxgloveMessage {
  std::string topic;
  std::uint64_t log_time_ns = 0;
  nlohmann::json body;
};

class FoxgloveClient {
 public:
  /// Connects to 127.0.0.1:`port` with the subprotocol, reads serverInfo and advertise. Throws
  /// when the server refuses the handshake or accepts another subprotocol.
  explicit FoxgloveClient(std::uint16_t port, const std::string& subprotocol = "foxglove.websocket.v1");
  ~FoxgloveClient();
  FoxgloveClient(const FoxgloveClient&) = delete;
  FoxgloveClient& operator=(const FoxgloveClient&) = delete;

  /// The next text message (before start()).
  nlohmann::json read_json();
  void send_text(const std::string& text);
  void send_binary(const std::string& bytes);

  /// Subscribes to the advertised channels whose topic starts with one of `prefixes` (all when
  /// empty); subscription id = channel id + 100.
  void subscribe(const std::vector<std::string>& prefixes = {});

  /// Reads on a thread of its own from now on.
  void start();
  void stop();

  std::vector<FoxgloveMessage> messages(const std::string& topic) const;
  std::size_t count(const std::string& topic) const;
  std::vector<nlohmann::json> statuses() const;
  bool closed() const;

  nlohmann::json server_info, advertise;
  std::string accepted_protocol;
  std::map<std::uint32_t, std::string> topics;  // channel id -> topic

 private:
  // As received: the JSON is parsed when a test asks for the topic (the reader keeps up with the
  // server under the sanitizers too).
  struct RawMessage {
    std::string topic;
    std::uint64_t log_time_ns = 0;
    std::string data;  // the whole message data, header and JSON
  };
  void read_loop();
  void decode(std::string data);

  WebSocketClient ws_;
  mutable std::mutex mutex_;
  std::map<std::uint32_t, std::string> by_subscription_;
  std::vector<RawMessage> messages_;
  std::vector<nlohmann::json> statuses_;
  bool closed_ = false;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

/// foxglove.PointCloud's points (x, y, z FLOAT32 at offsets 0, 4, 8), from its base64 data.
std::vector<std::array<float, 3>> decode_points(const nlohmann::json& cloud);

}  // namespace liod::test
