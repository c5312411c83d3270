#pragma once
// A Foxglove WebSocket client (foxglove.websocket.v1) for the live view's tests and benchmark: it
// connects as Foxglove Studio does, reads serverInfo and advertise, subscribes, and then collects
// every message data frame on a thread of its own, decoded (channel topic, log time, JSON).
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <cstring>
#include <cstdint>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace liod::test {

struct FoxgloveMessage {
  std::string topic;
  std::uint64_t log_time_ns = 0;
  nlohmann::json body;
};

// As received: the JSON is parsed when a test asks for the topic (the reader keeps up with the
// server under the sanitizers too).
struct RawFoxgloveMessage {
  std::string topic;
  std::uint64_t log_time_ns = 0;
  std::string payload;
};

class FoxgloveClient {
 public:
  /// Connects to 127.0.0.1:`port` with the subprotocol, reads serverInfo and advertise.
  explicit FoxgloveClient(std::uint16_t port, const std::string& subprotocol = "foxglove.websocket.v1")
      : ws_(ioc_) {
    namespace beast = boost::beast;
    boost::beast::get_lowest_layer(ws_).connect({boost::asio::ip::make_address("127.0.0.1"), port});
    ws_.set_option(beast::websocket::stream_base::decorator([subprotocol](beast::websocket::request_type& req) {
      req.set(beast::http::field::sec_websocket_protocol, subprotocol);
    }));
    beast::websocket::response_type res;
    ws_.handshake(res, "127.0.0.1:" + std::to_string(port), "/");
    accepted_protocol = std::string(res[beast::http::field::sec_websocket_protocol]);
    server_info = read_json();
    advertise = read_json();
    for (const auto& c : advertise.at("channels")) topics[c.at("id").get<std::uint32_t>()] = c.at("topic").get<std::string>();
  }

  ~FoxgloveClient() { stop(); }
  FoxgloveClient(const FoxgloveClient&) = delete;
  FoxgloveClient& operator=(const FoxgloveClient&) = delete;

  /// The next text message (before start()).
  nlohmann::json read_json() {
    boost::beast::flat_buffer b;
    ws_.read(b);
    return nlohmann::json::parse(boost::beast::buffers_to_string(b.data()));
  }

  void send_text(const std::string& text) {
    ws_.text(true);
    ws_.write(boost::asio::buffer(text));
  }
  void send_binary(const std::string& bytes) {
    ws_.binary(true);
    ws_.write(boost::asio::buffer(bytes));
  }

  /// Subscribes to the advertised channels whose topic starts with one of `prefixes` (all when
  /// empty); subscription id = channel id + 100.
  void subscribe(const std::vector<std::string>& prefixes = {}) {
    nlohmann::json subs = nlohmann::json::array();
    for (const auto& [id, topic] : topics) {
      bool wanted = prefixes.empty();
      for (const auto& p : prefixes) wanted = wanted || topic.rfind(p, 0) == 0;
      if (!wanted) continue;
      subs.push_back({{"id", id + 100}, {"channelId", id}});
      by_subscription_[id + 100] = topic;
    }
    send_text(nlohmann::json{{"op", "subscribe"}, {"subscriptions", subs}}.dump());
  }

  /// Reads on a thread of its own from now on.
  void start() {
    read_next();
    thread_ = std::thread([this] { ioc_.run(); });
  }

  void stop() {
    if (!thread_.joinable()) return;
    boost::asio::post(ioc_, [this] {
      boost::system::error_code ec;
      boost::beast::get_lowest_layer(ws_).socket().close(ec);
    });
    thread_.join();
  }

  std::vector<FoxgloveMessage> messages(const std::string& topic) const {
    std::lock_guard lock(mutex_);
    std::vector<FoxgloveMessage> out;
    for (const auto& m : messages_) {
      if (m.topic == topic) out.push_back({m.topic, m.log_time_ns, nlohmann::json::parse(m.payload)});
    }
    return out;
  }
  std::size_t count(const std::string& topic) const {
    std::lock_guard lock(mutex_);
    std::size_t n = 0;
    for (const auto& m : messages_) n += m.topic == topic ? 1 : 0;
    return n;
  }
  std::vector<nlohmann::json> statuses() const {
    std::lock_guard lock(mutex_);
    return statuses_;
  }
  bool closed() const {
    std::lock_guard lock(mutex_);
    return closed_;
  }

  nlohmann::json server_info, advertise;
  std::string accepted_protocol;
  std::map<std::uint32_t, std::string> topics;  // channel id -> topic

 private:
  void read_next() {
    ws_.async_read(buffer_, [this](boost::system::error_code ec, std::size_t) {
      if (ec) {
        std::lock_guard lock(mutex_);
        closed_ = true;
        return;
      }
      const std::string data = boost::beast::buffers_to_string(buffer_.data());
      buffer_.consume(buffer_.size());
      if (ws_.got_text()) {
        std::lock_guard lock(mutex_);
        statuses_.push_back(nlohmann::json::parse(data));
      } else {
        decode(data);
      }
      read_next();
    });
  }

  // Message data: opcode 0x01, uint32 subscription id, uint64 log time, little-endian; payload.
  void decode(const std::string& data) {
    if (data.size() < 13 || static_cast<std::uint8_t>(data[0]) != 0x01) throw std::runtime_error("not message data");
    auto le = [&](std::size_t at, int bytes) {
      std::uint64_t v = 0;
      for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | static_cast<std::uint8_t>(data[at + static_cast<std::size_t>(i)]);
      return v;
    };
    RawFoxgloveMessage m;
    m.topic = by_subscription_.at(static_cast<std::uint32_t>(le(1, 4)));
    m.log_time_ns = le(5, 8);
    m.payload = data.substr(13);
    std::lock_guard lock(mutex_);
    messages_.push_back(std::move(m));
  }

  boost::asio::io_context ioc_;
  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
  boost::beast::flat_buffer buffer_;
  std::map<std::uint32_t, std::string> by_subscription_;
  mutable std::mutex mutex_;
  std::vector<RawFoxgloveMessage> messages_;
  std::vector<nlohmann::json> statuses_;
  bool closed_ = false;
  std::thread thread_;
};

/// foxglove.PointCloud's points (x, y, z FLOAT32 at offsets 0, 4, 8), from its base64 data.
inline std::vector<std::array<float, 3>> decode_points(const nlohmann::json& cloud) {
  const std::string b64 = cloud.at("data").get<std::string>();
  std::vector<std::uint8_t> bytes;
  std::uint32_t acc = 0;
  int bits = 0;
  for (char c : b64) {
    int v = -1;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    else if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    else if (c >= '0' && c <= '9') v = c - '0' + 52;
    else if (c == '+') v = 62;
    else if (c == '/') v = 63;
    if (v < 0) continue;  // '=' padding
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      bytes.push_back(static_cast<std::uint8_t>(acc >> bits));
    }
  }
  const auto stride = cloud.at("point_stride").get<std::size_t>();
  std::vector<std::array<float, 3>> out;
  for (std::size_t i = 0; i + stride <= bytes.size(); i += stride) {
    std::array<float, 3> p{};
    for (int k = 0; k < 3; ++k) {
      std::uint32_t u = 0;
      for (int b = 3; b >= 0; --b) u = (u << 8) | bytes[i + static_cast<std::size_t>(4 * k + b)];
      std::memcpy(&p[static_cast<std::size_t>(k)], &u, 4);
    }
    out.push_back(p);
  }
  return out;
}

}  // namespace liod::test
