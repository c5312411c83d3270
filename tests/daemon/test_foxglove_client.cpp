// The tests' own WebSocket client (websocket_client.hpp, under foxglove_client.hpp) against a scripted server on 127.0.0.1
// that writes RFC 6455 frames byte by byte: the forms the live view's server may or may not use
// today (7-, 16- and 64-bit lengths, fragments with a ping between them, close), so that the
// client the Foxglove tests trust reads all of them and masks what it sends.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <set>
#include <stdexcept>
#include <thread>

#include "foxglove_client.hpp"
#include "wait_for.hpp"
#include "websocket_client.hpp"

namespace liod {
namespace {

using test::TcpConnection;

// A listening socket on 127.0.0.1, on a free port; accept() waits at most 5 s, and the accepted
// connection's reads at most 5 s each, so a client that misbehaves fails the test.
class Listener {
 public:
  Listener() : fd_(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0)) {
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof addr;
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), len) != 0 || ::listen(fd_, 1) != 0 ||
        ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
      throw std::runtime_error("listen on 127.0.0.1");
    }
    port_ = ntohs(addr.sin_port);
  }
  ~Listener() { ::close(fd_); }
  Listener(const Listener&) = delete;
  Listener& operator=(const Listener&) = delete;

  std::uint16_t port() const { return port_; }

  TcpConnection accept() {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 5000) != 1) throw std::runtime_error("no client within 5 s");
    const int c = ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (c < 0) throw std::runtime_error("accept");
    const timeval limit{5, 0};
    ::setsockopt(c, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
    return TcpConnection(TcpConnection::Adopt{c});
  }

 private:
  int fd_;
  std::uint16_t port_ = 0;
};

// A server frame (unmasked): `first` is FIN | opcode; the length in its minimal form (5.2).
std::string frame(std::uint8_t first, const std::string& payload) {
  std::string f(1, static_cast<char>(first));
  const std::uint64_t n = payload.size();
  const int ext = n < 126 ? 0 : n <= 0xFFFF ? 2 : 8;
  f.push_back(static_cast<char>(ext == 0 ? n : ext == 2 ? 126 : 127));
  for (int i = ext - 1; i >= 0; --i) f.push_back(static_cast<char>((n >> (8 * i)) & 0xFF));
  return f + payload;
}

struct ClientFrame {
  std::uint8_t first = 0;
  bool masked = false;
  std::string mask, payload;  // payload unmasked
};

ClientFrame read_client_frame(TcpConnection& c) {
  std::string head;
  c.read_exact(2, head);
  ClientFrame f;
  f.first = static_cast<std::uint8_t>(head[0]);
  f.masked = (static_cast<std::uint8_t>(head[1]) & 0x80) != 0;
  std::uint64_t n = static_cast<std::uint8_t>(head[1]) & 0x7F;
  if (n >= 126) {
    std::string ext;
    c.read_exact(n == 126 ? 2 : 8, ext);
    n = 0;
    for (char b : ext) n = (n << 8) | static_cast<std::uint8_t>(b);
  }
  if (f.masked) c.read_exact(4, f.mask);
  c.read_exact(static_cast<std::size_t>(n), f.payload);
  for (std::size_t i = 0; f.masked && i < f.payload.size(); ++i) f.payload[i] = static_cast<char>(f.payload[i] ^ f.mask[i % 4]);
  return f;
}

// Message data (Foxglove): 0x01, subscription id (uint32), log time (uint64), little-endian.
std::string message_data(std::uint32_t subscription, std::uint64_t log_time_ns, const std::string& json) {
  std::string m(1, '\x01');
  for (int i = 0; i < 4; ++i) m.push_back(static_cast<char>((subscription >> (8 * i)) & 0xFF));
  for (int i = 0; i < 8; ++i) m.push_back(static_cast<char>((log_time_ns >> (8 * i)) & 0xFF));
  return m + json;
}

// Reads the upgrade request and answers it with `status`, the subprotocol `protocol` and the right
// accept key (or `accept` when not empty), then serverInfo and advertise.
void answer_handshake(TcpConnection& c, const std::string& protocol, const std::string& accept = {}, const std::string& status = "101 Switching Protocols") {
  const std::string request = c.read_until("\r\n\r\n", 16384);
  EXPECT_NE(request.find("\r\nSec-WebSocket-Version: 13\r\n"), std::string::npos) << request;
  EXPECT_NE(request.find("\r\nSec-WebSocket-Protocol: foxglove.websocket.v1\r\n"), std::string::npos) << request;
  const std::string field = "\r\nSec-WebSocket-Key: ";
  const std::size_t at = request.find(field) + field.size();
  const std::string key = request.substr(at, request.find("\r\n", at) - at);
  EXPECT_EQ(key.size(), 24U) << key;  // 16 random bytes in base64
  c.write("HTTP/1.1 " + status + "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Accept: " +
          (accept.empty() ? test::websocket_accept(key) : accept) + "\r\nSec-WebSocket-Protocol: " + protocol + "\r\n\r\n" +
          frame(0x81, R"({"op":"serverInfo"})") +
          frame(0x81, R"({"op":"advertise","channels":[{"id":1,"topic":"/a"},{"id":2,"topic":"/b"}]})"));
}

TEST(FoxgloveClient, AcceptKeyOfRfc6455Example) {
  EXPECT_EQ(test::websocket_accept("dGhlIHNhbXBsZSBub25jZQ=="), "s3pPLMBiTxaQ9kYGzzhZRbK+xOo=");  // RFC 6455 1.3
}

TEST(FoxgloveClient, ReadsEveryFrameFormAndMasksItsOwn) {
  Listener listener;
  const std::string pad(70000, 'x');  // a 64-bit length
  const std::string status = R"({"op":"status","level":2,"message":")" + std::string(200, 'y') + "\"}";  // a 16-bit one
  std::vector<ClientFrame> received;
  std::thread server([&] {
    try {
      auto c = listener.accept();
      answer_handshake(c, "foxglove.websocket.v1");
      // One message data in three fragments, a ping between the first two (5.4 allows it).
      const std::string b = message_data(102, 7, R"({"fragmented":true})");
      c.write(frame(0x02, b.substr(0, 5)) + frame(0x89, "hi") + frame(0x00, b.substr(5, 10)) + frame(0x80, b.substr(15)));
      for (int i = 0; i < 2; ++i) received.push_back(read_client_frame(c));  // the subscription, then the pong (reader)
      c.write(frame(0x82, message_data(101, 0x0102030405060708ULL, R"({"pad":")" + pad + "\"}")) + frame(0x81, status) +
              frame(0x88, "\x03\xE8"));  // close, 1000
      received.push_back(read_client_frame(c));  // the close echoed
    } catch (const std::exception& e) {
      ADD_FAILURE() << "server: " << e.what();
    }
  });
  test::FoxgloveClient client(listener.port());
  EXPECT_EQ(client.accepted_protocol, "foxglove.websocket.v1");
  EXPECT_EQ(client.server_info.at("op"), "serverInfo");
  EXPECT_EQ(client.topics, (std::map<std::uint32_t, std::string>{{1, "/a"}, {2, "/b"}}));
  client.subscribe();
  client.start();
  EXPECT_TRUE(test::wait_for([&] { return client.closed(); }, std::chrono::seconds(10)));
  server.join();

  ASSERT_EQ(received.size(), 3U);
  EXPECT_EQ(received[0].first, 0x81);
  const auto subscribe = nlohmann::json::parse(received[0].payload);
  EXPECT_EQ(subscribe.at("op"), "subscribe");
  EXPECT_EQ(subscribe.at("subscriptions").size(), 2U);
  EXPECT_EQ(received[1].first, 0x8A);  // pong, with the ping's payload
  EXPECT_EQ(received[1].payload, "hi");
  EXPECT_EQ(received[2].first, 0x88);
  EXPECT_EQ(received[2].payload, "\x03\xE8");
  std::set<std::string> masks;
  for (const auto& f : received) {
    EXPECT_TRUE(f.masked);
    masks.insert(f.mask);
  }
  EXPECT_EQ(masks.size(), 3U);  // a fresh random key each frame

  const auto a = client.messages("/a");
  ASSERT_EQ(a.size(), 1U);
  EXPECT_EQ(a[0].log_time_ns, 0x0102030405060708ULL);
  EXPECT_EQ(a[0].body.at("pad"), pad);
  const auto b = client.messages("/b");
  ASSERT_EQ(b.size(), 1U);
  EXPECT_EQ(b[0].log_time_ns, 7U);
  EXPECT_EQ(b[0].body.at("fragmented"), true);
  ASSERT_EQ(client.statuses().size(), 1U);
  EXPECT_EQ(client.statuses()[0].at("level"), 2);
}

// A handshake that fails any check of RFC 6455 4.1 throws from the constructor; a right one, the
// control, does not.
TEST(FoxgloveClient, RefusesAWrongHandshake) {
  struct Case {
    std::string protocol, accept, status, error;
  };
  const std::vector<Case> cases{{"foxglove.websocket.v1", "", "101 Switching Protocols", ""},
                                {"foxglove.websocket.v1", "s3pPLMBiTxaQ9kYGzzhZRbK+xOo=", "101 Switching Protocols", "Sec-WebSocket-Accept"},
                                {"other.protocol", "", "101 Switching Protocols", "subprotocol"},
                                {"foxglove.websocket.v1", "", "400 Bad Request", "refused"}};
  for (const auto& k : cases) {
    Listener listener;
    std::thread server([&] {
      try {
        auto c = listener.accept();
        answer_handshake(c, k.protocol, k.accept, k.status);
        std::string rest;
        c.read_exact(1, rest);  // until the client is gone
      } catch (const std::exception&) {
      }
    });
    std::string error;
    try {
      test::FoxgloveClient client(listener.port());
    } catch (const std::exception& e) {
      error = e.what();
    }
    server.join();
    if (k.error.empty()) {
      EXPECT_EQ(error, "");
    } else {
      EXPECT_NE(error.find(k.error), std::string::npos) << k.status << " " << k.protocol << ": '" << error << "'";
    }
  }
}

}  // namespace
}  // namespace liod
