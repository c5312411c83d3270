// The tests' Foxglove client (foxglove_client.hpp) over websocket_client.hpp. The message data
// header's fields are read byte by byte in their little-endian order, whatever the host's.
#include "foxglove_client.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace liod::test {

FoxgloveClient::FoxgloveClient(std::uint16_t port, const std::string& subprotocol) : ws_(port, subprotocol) {
  accepted_protocol = ws_.accepted_protocol();
  server_info = read_json();
  advertise = read_json();
  for (const auto& c : advertise.at("channels")) topics[c.at("id").get<std::uint32_t>()] = c.at("topic").get<std::string>();
}

FoxgloveClient::~FoxgloveClient() { stop(); }

nlohmann::json FoxgloveClient::read_json() {
  const WebSocketClient::Message m = ws_.read();
  if (!m.text) throw std::runtime_error("Foxglove: a binary message where a JSON one was due");
  return nlohmann::json::parse(m.data);
}

void FoxgloveClient::send_text(const std::string& text) { ws_.send(WebSocketClient::kText, text); }
void FoxgloveClient::send_binary(const std::string& bytes) { ws_.send(WebSocketClient::kBinary, bytes); }

void FoxgloveClient::subscribe(const std::vector<std::string>& prefixes) {
  nlohmann::json subs = nlohmann::json::array();
  {
    std::lock_guard lock(mutex_);
    for (const auto& [id, topic] : topics) {
      bool wanted = prefixes.empty();
      for (const auto& p : prefixes) wanted = wanted || topic.rfind(p, 0) == 0;
      if (!wanted) continue;
      subs.push_back({{"id", id + 100}, {"channelId", id}});
      by_subscription_[id + 100] = topic;
    }
  }
  send_text(nlohmann::json{{"op", "subscribe"}, {"subscriptions", subs}}.dump());
}

void FoxgloveClient::start() {
  thread_ = std::thread([this] { read_loop(); });
}

void FoxgloveClient::stop() {
  if (!thread_.joinable()) return;
  stopping_ = true;
  ws_.shutdown();
  thread_.join();
}

void FoxgloveClient::read_loop() {
  try {
    for (;;) {
      WebSocketClient::Message m = ws_.read();
      if (m.text) {
        auto status = nlohmann::json::parse(m.data);
        std::lock_guard lock(mutex_);
        statuses_.push_back(std::move(status));
      } else {
        decode(std::move(m.data));
      }
    }
  } catch (const WebSocketClient::Closed&) {
  } catch (const std::exception& e) {
    if (!stopping_) std::fprintf(stderr, "FoxgloveClient: %s\n", e.what());
  }
  std::lock_guard lock(mutex_);
  closed_ = true;
}

// Message data: opcode 0x01, uint32 subscription id, uint64 log time, little-endian; payload.
void FoxgloveClient::decode(std::string data) {
  const auto byte_at = [&](std::size_t i) { return static_cast<std::uint8_t>(data[i]); };
  if (data.size() < 13 || byte_at(0) != 0x01) throw std::runtime_error("Foxglove: a binary message that is not message data");
  const auto le = [&](std::size_t at, std::size_t bytes) {
    std::uint64_t v = 0;
    for (std::size_t i = bytes; i-- > 0;) v = (v << 8) | byte_at(at + i);
    return v;
  };
  RawMessage m;
  m.log_time_ns = le(5, 8);
  const auto subscription = static_cast<std::uint32_t>(le(1, 4));
  m.data = std::move(data);  // the JSON from byte 13 on, parsed when asked for (no copy here)
  std::lock_guard lock(mutex_);
  m.topic = by_subscription_.at(subscription);
  messages_.push_back(std::move(m));
}

std::vector<FoxgloveMessage> FoxgloveClient::messages(const std::string& topic) const {
  std::lock_guard lock(mutex_);
  std::vector<FoxgloveMessage> out;
  for (const auto& m : messages_) {
    if (m.topic == topic) out.push_back({m.topic, m.log_time_ns, nlohmann::json::parse(m.data.begin() + 13, m.data.end())});
  }
  return out;
}

std::size_t FoxgloveClient::count(const std::string& topic) const {
  std::lock_guard lock(mutex_);
  return static_cast<std::size_t>(std::count_if(messages_.begin(), messages_.end(), [&](const RawMessage& m) { return m.topic == topic; }));
}

std::vector<nlohmann::json> FoxgloveClient::statuses() const {
  std::lock_guard lock(mutex_);
  return statuses_;
}

bool FoxgloveClient::closed() const {
  std::lock_guard lock(mutex_);
  return closed_;
}

std::vector<std::array<float, 3>> decode_points(const nlohmann::json& cloud) {
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
    for (std::size_t k = 0; k < 3; ++k) {
      std::uint32_t u = 0;
      for (std::size_t b = 4; b-- > 0;) u = (u << 8) | bytes[i + 4 * k + b];
      std::memcpy(&p[k], &u, 4);
    }
    out.push_back(p);
  }
  return out;
}

}  // namespace liod::test
