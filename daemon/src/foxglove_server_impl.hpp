#pragma once
// The live view's server internals (foxglove_server.cpp alone includes this): the io thread's
// state (FoxgloveServer::Impl) and one client's connection (Session). Boost.Beast is here, out of
// every header the rest of liod includes.

#include <pthread.h>

#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <deque>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "foxglove_messages.hpp"
#include "liod/daemon/foxglove_server.hpp"

namespace liod {
namespace foxglove {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

constexpr const char* kSubprotocol = "foxglove.websocket.v1";
// Tasks the pipeline may have queued for the io thread before further posts are dropped: the
// pipeline never waits, and an io thread starved of CPU holds at most this much. Scans (100k
// points each) have a bound of their own.
constexpr int kMaxPendingPosts = 512;
constexpr int kMaxPendingScans = 2;
constexpr std::size_t kMaxClientMessage = 1 << 20;  // a client's JSON requests are small
constexpr auto kHandshakeTimeout = std::chrono::seconds(10);
// A viewer that neither reads nor answers pings for this long is gone (Beast closes it).
constexpr auto kIdleTimeout = std::chrono::seconds(30);
// The io thread is the daemon's least urgent work: below the drivers and the odometry.
constexpr int kViewerNice = 10;

struct Outgoing {
  std::array<std::uint8_t, 13> header{};
  bool binary = false;
  bool droppable = false;  // message data: a slow client loses the oldest; serverInfo/advertise stay
  std::shared_ptr<const std::string> payload;
  std::size_t size() const { return payload->size() + (binary ? header.size() : 0); }
};

// True when the comma-separated header value lists `token`.
inline bool lists_token(std::string_view value, std::string_view token) {
  while (!value.empty()) {
    const std::size_t comma = value.find(',');
    std::string_view item = value.substr(0, comma);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    while (!item.empty() && item.back() == ' ') item.remove_suffix(1);
    if (item == token) return true;
    if (comma == std::string_view::npos) break;
    value.remove_prefix(comma + 1);
  }
  return false;
}

class Session;

}  // namespace foxglove

class FoxgloveServer::Impl {
 public:
  Impl(const ViewerConfig& config, const ExtrinsicsConfig& extrinsics, std::uint16_t port);
  ~Impl();

  template <class F>
  void post(F&& task, std::atomic<int>& pending, int limit);

  void accept();
  void remove(foxglove::Session* session);
  void update_interest();
  bool subscribed(foxglove::ChannelId channel) const;
  void broadcast(foxglove::ChannelId channel, double time, std::string payload);
  void on_tick();
  void handle_pose(const pose::PoseMessage& m);

  boost::asio::io_context ioc;  // first: destroyed last, after the sockets and timers that use it
  ViewerConfig config;
  ExtrinsicsConfig extrinsics;
  boost::asio::ip::tcp::acceptor acceptor{ioc};
  boost::asio::steady_timer tick{ioc};
  std::vector<std::shared_ptr<foxglove::Session>> sessions;
  foxglove::ViewState view;
  bool map_dirty = false, trajectory_dirty = false, keyframes_dirty = false;
  std::string session_id;
  std::uint16_t bound_port = 0;  // set before the io thread starts: read from any thread
  std::atomic<bool> scans_wanted{false};
  std::atomic<int> pending_posts{0}, pending_scans{0};
  std::atomic<std::uint64_t> clients{0}, connections{0}, refused{0}, sent{0}, dropped{0}, posts_dropped{0}, bad_requests{0};
  std::thread thread;
};

namespace foxglove {

class Session : public std::enable_shared_from_this<Session> {
 public:
  Session(tcp::socket socket, FoxgloveServer::Impl& server) : ws_(std::move(socket)), server_(server) {}

  void start() {
    parser_.emplace();
    parser_->header_limit(16384);
    beast::get_lowest_layer(ws_).expires_after(kHandshakeTimeout);
    http::async_read(ws_.next_layer(), buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_request(ec); });
  }

  bool subscribed(ChannelId channel) const { return by_channel_.count(channel) != 0; }

  void send_text(std::string text) {
    Outgoing o;
    o.payload = std::make_shared<const std::string>(std::move(text));
    enqueue(std::move(o));
  }

  void send_message(ChannelId channel, std::uint64_t time_ns, const std::shared_ptr<const std::string>& payload) {
    const auto it = by_channel_.find(channel);
    if (it == by_channel_.end()) return;
    Outgoing o;
    o.header = foxglove::message_header(it->second, time_ns);
    o.binary = true;
    o.droppable = true;
    o.payload = payload;
    enqueue(std::move(o));
  }

  void close() {
    if (closed_) return;
    closed_ = true;
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
    beast::get_lowest_layer(ws_).socket().close(ec);
    queue_.clear();
    queued_bytes_ = 0;
    server_.remove(this);
  }

 private:
  void on_request(beast::error_code ec) {
    if (ec) {
      ++server_.refused;  // not HTTP, too long, or gone before the handshake
      return close();
    }
    const auto& req = parser_->get();
    const auto protocols = req[http::field::sec_websocket_protocol];
    if (!websocket::is_upgrade(req) || !lists_token({protocols.data(), protocols.size()}, kSubprotocol)) {
      ++server_.refused;
      auto res = std::make_shared<http::response<http::string_body>>(http::status::bad_request, req.version());
      res->set(http::field::content_type, "text/plain");
      res->body() = "liod: a Foxglove WebSocket endpoint (subprotocol foxglove.websocket.v1)\n";
      res->prepare_payload();
      http::async_write(ws_.next_layer(), *res, [self = shared_from_this(), res](beast::error_code, std::size_t) { self->close(); });
      return;
    }
    beast::get_lowest_layer(ws_).expires_never();
    websocket::stream_base::timeout timeout{kHandshakeTimeout, kIdleTimeout, true};
    ws_.set_option(timeout);
    ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& res) {
      res.set(http::field::sec_websocket_protocol, kSubprotocol);
      res.set(http::field::server, "liod");
    }));
    ws_.read_message_max(kMaxClientMessage);
    ws_.async_accept(req, [self = shared_from_this()](beast::error_code e) { self->on_accept(e); });
  }

  void on_accept(beast::error_code ec) {
    if (ec) return close();
    parser_.reset();
    ++server_.connections;
    send_text(foxglove::server_info_json(server_.session_id));
    send_text(foxglove::advertise_json());
    read();
  }

  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec) return close();
    if (ws_.got_text()) {
      handle_text(beast::buffers_to_string(buffer_.data()));
    } else {
      reject("binary messages are not accepted (the server has no clientPublish capability)");
    }
    buffer_.consume(buffer_.size());
    read();
  }

  void reject(const std::string& why) {
    ++server_.bad_requests;
    send_text(foxglove::status_json(2, why));
  }

  void handle_text(const std::string& text) {
    const auto msg = nlohmann::json::parse(text, nullptr, false);
    if (msg.is_discarded() || !msg.is_object() || !msg.contains("op") || !msg["op"].is_string()) {
      return reject("not a JSON object with an \"op\"");
    }
    const std::string op = msg["op"].get<std::string>();
    try {
      if (op == "subscribe") subscribe(msg.at("subscriptions"));
      else if (op == "unsubscribe") unsubscribe(msg.at("subscriptionIds"));
      else reject("unsupported op \"" + op + "\"");
    } catch (const std::exception& e) {
      reject("malformed " + op + ": " + e.what());
    }
    server_.update_interest();
  }

  void subscribe(const nlohmann::json& list) {
    for (const auto& s : list) {
      const auto id = s.at("id").get<std::uint32_t>();
      const auto channel = s.at("channelId").get<std::uint32_t>();
      if (channel < foxglove::kScan || channel > foxglove::kChannelCount) {
        reject("no channel " + std::to_string(channel));
      } else if (by_id_.count(id) != 0) {
        reject("subscription id " + std::to_string(id) + " is in use");
      } else if (by_channel_.count(static_cast<ChannelId>(channel)) != 0) {
        reject("channel " + std::to_string(channel) + " is already subscribed");
      } else {
        by_id_[id] = static_cast<ChannelId>(channel);
        by_channel_[static_cast<ChannelId>(channel)] = id;
      }
    }
    server_.map_dirty = server_.trajectory_dirty = server_.keyframes_dirty = true;  // a newcomer gets them at the next tick
  }

  void unsubscribe(const nlohmann::json& list) {
    for (const auto& s : list) {
      const auto id = s.get<std::uint32_t>();
      const auto it = by_id_.find(id);
      if (it == by_id_.end()) {
        reject("no subscription " + std::to_string(id));
        continue;
      }
      by_channel_.erase(it->second);
      by_id_.erase(it);
    }
  }

  void enqueue(Outgoing o) {
    if (closed_) return;
    queued_bytes_ += o.size();
    queue_.push_back(std::move(o));
    // Drop the oldest message data while the queue is over its bound (never the newest).
    for (std::size_t i = 0; queued_bytes_ > static_cast<std::size_t>(server_.config.client_queue_bytes) && i + 1 < queue_.size();) {
      if (!queue_[i].droppable) {
        ++i;
        continue;
      }
      queued_bytes_ -= queue_[i].size();
      queue_.erase(queue_.begin() + static_cast<std::ptrdiff_t>(i));
      ++server_.dropped;
    }
    if (!writing_) write_next();
  }

  void write_next() {
    if (queue_.empty() || closed_) return;
    in_flight_ = std::move(queue_.front());
    queue_.pop_front();
    queued_bytes_ -= in_flight_.size();
    writing_ = true;
    ws_.binary(in_flight_.binary);
    auto done = [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_write(ec); };
    if (in_flight_.binary) {
      const std::array<asio::const_buffer, 2> buffers{asio::buffer(in_flight_.header), asio::buffer(*in_flight_.payload)};
      ws_.async_write(buffers, std::move(done));
    } else {
      ws_.async_write(asio::buffer(*in_flight_.payload), std::move(done));
    }
  }

  void on_write(beast::error_code ec) {
    writing_ = false;
    if (ec) return close();
    if (in_flight_.binary) ++server_.sent;
    in_flight_.payload.reset();
    write_next();
  }

  // deflateSupported = false: liod never negotiates permessage-deflate (RFC 7692), and without it
  // the instantiation leaves Beast's deflate code out (gcc -O3 compiles this file in about 30 %
  // less time; clang -O2 in the sanitizer trees, in about the same).
  websocket::stream<beast::tcp_stream, false> ws_;
  FoxgloveServer::Impl& server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::empty_body>> parser_;
  std::map<std::uint32_t, ChannelId> by_id_;
  std::map<ChannelId, std::uint32_t> by_channel_;
  std::deque<Outgoing> queue_;
  std::size_t queued_bytes_ = 0;
  Outgoing in_flight_;
  bool writing_ = false;
  bool closed_ = false;
};

}  // namespace foxglove
}  // namespace liod
