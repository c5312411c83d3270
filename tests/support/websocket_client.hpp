#pragma once
// A WebSocket client (RFC 6455) on POSIX sockets, for the live view's tests (foxglove_client.hpp).
// It is written from the RFC rather than taken from Boost.Beast, which the server uses: an
// implementation independent of the server's tests its handshake and framing better than Beast
// talking to Beast would (a misreading shared by both ends would go unseen), and the tests then
// compile without Beast, the slowest headers of the build. A client for tests: blocking I/O to
// 127.0.0.1, no extensions (liod negotiates none). websocket_client.cpp has the implementation.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>

namespace liod::test {

/// A blocking TCP connection to 127.0.0.1:port (or an accepted socket it takes over). The bytes
/// read past what a call asked for stay buffered for the next call.
class TcpConnection {
 public:
  struct Adopt {
    int fd;
  };
  explicit TcpConnection(std::uint16_t port);
  explicit TcpConnection(Adopt socket) : fd_(socket.fd) {}
  ~TcpConnection();
  TcpConnection(const TcpConnection&) = delete;
  TcpConnection& operator=(const TcpConnection&) = delete;

  /// All of `bytes`; throws when the peer is gone.
  void write(std::string_view bytes);
  /// Everything up to and including `delimiter`; throws at end of stream or past `limit` bytes.
  std::string read_until(std::string_view delimiter, std::size_t limit);
  /// Appends exactly `n` bytes to `out`; throws at end of stream.
  void read_exact(std::size_t n, std::string& out);
  /// Shuts both directions down: a read blocked on another thread returns (end of stream).
  void shutdown();

 private:
  bool fill();  // false at end of stream

  // Received, not yet read: in_[in_begin_, in_end_). Not a std::string, whose resize would zero
  // the whole chunk before each recv (costly under the sanitizers, where the reader must keep up).
  static constexpr std::size_t kBufferBytes = 256 * 1024;
  int fd_ = -1;
  std::unique_ptr<char[]> in_{new char[kBufferBytes]};
  std::size_t in_begin_ = 0, in_end_ = 0;
};

/// One WebSocket connection to 127.0.0.1:port: the opening handshake (4.1) in the constructor,
/// then whole messages. One thread may read while others send.
class WebSocketClient {
 public:
  enum Opcode : std::uint8_t { kText = 0x1, kBinary = 0x2, kClose = 0x8, kPing = 0x9, kPong = 0xA };
  struct Message {
    bool text = false;
    std::string data;
  };
  /// The server's close frame (5.5.1): the connection is over.
  struct Closed : std::runtime_error {
    Closed() : std::runtime_error("WebSocket: closed by the server") {}
  };

  /// Throws when the server refuses the handshake, fails one of 4.1's checks, or accepts another
  /// subprotocol than `subprotocol` (or none).
  WebSocketClient(std::uint16_t port, const std::string& subprotocol);

  const std::string& accepted_protocol() const { return protocol_; }
  /// The next text or binary message, its fragments joined (5.4); answers pings on the way
  /// (5.5.2), and a close frame (then throws Closed).
  Message read();
  /// One unfragmented frame, masked with a fresh random key (5.3).
  void send(Opcode opcode, std::string_view payload);
  /// Unblocks a read on another thread (it then throws).
  void shutdown() { conn_.shutdown(); }

 private:
  TcpConnection conn_;
  std::mutex write_mutex_;  // a test's thread sends requests, the reader answers pings
  std::string protocol_;
};

/// Sec-WebSocket-Accept for a Sec-WebSocket-Key (RFC 6455 4.2.2): base64(SHA-1(key + GUID)).
std::string websocket_accept(const std::string& key);

}  // namespace liod::test
