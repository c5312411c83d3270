// The tests' WebSocket client (websocket_client.hpp): RFC 6455 on POSIX sockets. Every
// multi-byte field is read and written byte by byte in network (big-endian) order, whatever the
// host's.
#include "websocket_client.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <map>
#include <random>
#include <system_error>

namespace liod::test {
namespace {

constexpr std::size_t kMaxMessage = std::size_t{1} << 28;  // far above liod's largest (a map cloud)
constexpr std::size_t kMaxResponseHeader = 16384;

std::uint8_t byte_at(std::string_view s, std::size_t i) { return static_cast<std::uint8_t>(s[i]); }

std::uint32_t rotl(std::uint32_t v, int n) { return (v << n) | (v >> (32 - n)); }

// SHA-1 (FIPS 180-4), for the handshake's accept key only (RFC 6455 4.1).
std::array<std::uint8_t, 20> sha1(std::string_view data) {
  std::string m(data);
  const std::uint64_t bits = static_cast<std::uint64_t>(data.size()) * 8;
  m.push_back('\x80');
  while (m.size() % 64 != 56) m.push_back('\0');
  for (int i = 7; i >= 0; --i) m.push_back(static_cast<char>((bits >> (8 * i)) & 0xFF));
  std::array<std::uint32_t, 5> h{0x67452301, 0xEFCDAB89, 0x98BADCFE, 0x10325476, 0xC3D2E1F0};
  for (std::size_t block = 0; block < m.size(); block += 64) {
    std::array<std::uint32_t, 80> w{};
    for (std::size_t t = 0; t < 16; ++t) {
      for (std::size_t b = 0; b < 4; ++b) w[t] = (w[t] << 8) | byte_at(m, block + 4 * t + b);
    }
    for (std::size_t t = 16; t < 80; ++t) w[t] = rotl(w[t - 3] ^ w[t - 8] ^ w[t - 14] ^ w[t - 16], 1);
    std::uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4];
    for (std::size_t t = 0; t < 80; ++t) {
      std::uint32_t f = 0, k = 0;
      if (t < 20) f = (b & c) | (~b & d), k = 0x5A827999;
      else if (t < 40) f = b ^ c ^ d, k = 0x6ED9EBA1;
      else if (t < 60) f = (b & c) | (b & d) | (c & d), k = 0x8F1BBCDC;
      else f = b ^ c ^ d, k = 0xCA62C1D6;
      const std::uint32_t next = rotl(a, 5) + f + e + k + w[t];
      e = d, d = c, c = rotl(b, 30), b = a, a = next;
    }
    h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e;
  }
  std::array<std::uint8_t, 20> out{};
  for (std::size_t i = 0; i < 20; ++i) out[i] = static_cast<std::uint8_t>(h[i / 4] >> (24 - 8 * (i % 4)));
  return out;
}

std::string base64(const std::uint8_t* data, std::size_t n) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < n; i += 3) {
    const std::uint32_t v = (std::uint32_t{data[i]} << 16) | (i + 1 < n ? std::uint32_t{data[i + 1]} << 8 : 0U) |
                            (i + 2 < n ? std::uint32_t{data[i + 2]} : 0U);
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(i + 1 < n ? kAlphabet[(v >> 6) & 63] : '=');
    out.push_back(i + 2 < n ? kAlphabet[v & 63] : '=');
  }
  return out;
}

// The handshake's key and every frame's mask come from here: RFC 6455 5.3 wants masks a proxy
// cannot predict, which a generator seeded from the system's entropy gives a test client.
std::uint8_t random_byte() {
  thread_local std::mt19937 rng{std::random_device{}()};
  return static_cast<std::uint8_t>(rng() & 0xFF);
}

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

// True when the comma-separated header value lists `token` (case-insensitive).
bool lists_token(const std::string& value, const std::string& token) {
  std::size_t at = 0;
  while (at <= value.size()) {
    const std::size_t comma = std::min(value.find(',', at), value.size());
    if (lower(trim(value.substr(at, comma - at))) == lower(token)) return true;
    at = comma + 1;
  }
  return false;
}

// The handshake response's status line and its header fields (names lower-cased).
struct HttpResponse {
  std::string status_line;
  std::map<std::string, std::string> fields;
};

HttpResponse parse_response(const std::string& text) {
  HttpResponse r;
  std::size_t at = text.find("\r\n");
  r.status_line = text.substr(0, at);
  while (at != std::string::npos && at + 2 < text.size()) {
    const std::size_t end = text.find("\r\n", at + 2);
    const std::string line = text.substr(at + 2, end - at - 2);
    const std::size_t colon = line.find(':');
    if (colon != std::string::npos) r.fields[lower(trim(line.substr(0, colon)))] = trim(line.substr(colon + 1));
    at = end;
  }
  return r;
}

std::runtime_error protocol_error(const std::string& what) { return std::runtime_error("WebSocket: " + what); }
}  // namespace

// ---------------------------------------------------------------------------------------------
// TcpConnection

TcpConnection::TcpConnection(std::uint16_t port) : fd_(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0)) {
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "socket");
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const int error = errno;
    ::close(fd_);
    throw std::system_error(error, std::generic_category(), "connect to 127.0.0.1:" + std::to_string(port));
  }
  const int one = 1;
  ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);  // each frame goes out in one write
}

TcpConnection::~TcpConnection() {
  if (fd_ >= 0) ::close(fd_);
}

void TcpConnection::write(std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw std::system_error(errno, std::generic_category(), "send");
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
}

bool TcpConnection::fill() {
  if (in_begin_ == in_end_) in_begin_ = in_end_ = 0;
  if (in_end_ == kBufferBytes) {  // only read_until leaves bytes unread: move them to the front
    std::memmove(in_.get(), in_.get() + in_begin_, in_end_ - in_begin_);
    in_end_ -= in_begin_;
    in_begin_ = 0;
  }
  ssize_t n = 0;
  do {
    n = ::recv(fd_, in_.get() + in_end_, kBufferBytes - in_end_, 0);
  } while (n < 0 && errno == EINTR);
  if (n < 0) throw std::system_error(errno, std::generic_category(), "recv");
  in_end_ += static_cast<std::size_t>(n);
  return n > 0;
}

std::string TcpConnection::read_until(std::string_view delimiter, std::size_t limit) {
  limit = std::min(limit, kBufferBytes);
  for (;;) {
    const std::string_view unread(in_.get() + in_begin_, in_end_ - in_begin_);
    const std::size_t at = unread.find(delimiter);
    if (at != std::string_view::npos) {
      std::string out(unread.substr(0, at + delimiter.size()));
      in_begin_ += out.size();
      return out;
    }
    if (unread.size() >= limit) throw std::runtime_error("no delimiter within " + std::to_string(limit) + " bytes");
    if (!fill()) throw std::runtime_error("connection closed by the peer");
  }
}

void TcpConnection::read_exact(std::size_t n, std::string& out) {
  while (n > 0) {
    if (in_begin_ == in_end_ && !fill()) throw std::runtime_error("connection closed by the peer");
    const std::size_t take = std::min(n, in_end_ - in_begin_);
    out.append(in_.get() + in_begin_, take);
    in_begin_ += take;
    n -= take;
  }
}

void TcpConnection::shutdown() { ::shutdown(fd_, SHUT_RDWR); }

// ---------------------------------------------------------------------------------------------
// The opening handshake (RFC 6455 4.1)

std::string websocket_accept(const std::string& key) {
  const auto digest = sha1(key + "258EAFA5-E914-47DA-95CA-C5AB0DC85B11");
  return base64(digest.data(), digest.size());
}

WebSocketClient::WebSocketClient(std::uint16_t port, const std::string& subprotocol) : conn_(port) {
  std::array<std::uint8_t, 16> nonce{};
  for (auto& b : nonce) b = random_byte();
  const std::string key = base64(nonce.data(), nonce.size());
  conn_.write("GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
              "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: " + key +
              "\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: " + subprotocol + "\r\n\r\n");
  const HttpResponse res = parse_response(conn_.read_until("\r\n\r\n", kMaxResponseHeader));
  const auto field = [&](const std::string& name) {
    const auto it = res.fields.find(name);
    return it == res.fields.end() ? std::string() : it->second;
  };
  // Any status but 101 is a refusal; so is a 101 that fails any of 4.1's checks.
  if (res.status_line.rfind("HTTP/1.1 101", 0) != 0) throw protocol_error("handshake refused: " + res.status_line);
  if (lower(field("upgrade")) != "websocket") throw protocol_error("101 without Upgrade: websocket");
  if (!lists_token(field("connection"), "upgrade")) throw protocol_error("101 without Connection: Upgrade");
  if (field("sec-websocket-accept") != websocket_accept(key)) throw protocol_error("wrong Sec-WebSocket-Accept");
  if (!field("sec-websocket-extensions").empty()) throw protocol_error("an extension the client did not offer");
  protocol_ = field("sec-websocket-protocol");
  // The tests' clients have nothing to say without their subprotocol (4.1: one not offered fails).
  if (protocol_ != subprotocol) throw protocol_error("subprotocol '" + protocol_ + "' accepted, not '" + subprotocol + "'");
}

// ---------------------------------------------------------------------------------------------
// Frames (RFC 6455 5)

WebSocketClient::Message WebSocketClient::read() {
  Message message;
  bool in_message = false;
  for (;;) {
    std::string head;
    conn_.read_exact(2, head);
    const std::uint8_t b0 = byte_at(head, 0), b1 = byte_at(head, 1);
    const bool fin = (b0 & 0x80) != 0;
    const std::uint8_t opcode = b0 & 0x0F;
    if ((b0 & 0x70) != 0) throw protocol_error("RSV bits set without a negotiated extension (5.2)");
    if ((b1 & 0x80) != 0) throw protocol_error("a masked frame from the server (5.1)");
    std::uint64_t length = b1 & 0x7F;
    if (length >= 126) {
      const std::size_t n = length == 126 ? 2 : 8;
      std::string ext;
      conn_.read_exact(n, ext);
      length = 0;
      for (std::size_t i = 0; i < n; ++i) length = (length << 8) | byte_at(ext, i);
      // 5.2: the most significant bit is 0, and the length takes the fewest bytes it can.
      if ((n == 2 && length < 126) || (n == 8 && (length <= 0xFFFF || (length >> 63) != 0))) {
        throw protocol_error("payload length not in its minimal form (5.2)");
      }
    }
    if (length > kMaxMessage - message.data.size()) throw protocol_error("message over " + std::to_string(kMaxMessage) + " bytes");
    if ((opcode & 0x8) != 0) {  // a control frame (5.5)
      if (!fin || length > 125) throw protocol_error("fragmented or long control frame (5.5)");
      std::string payload;
      conn_.read_exact(static_cast<std::size_t>(length), payload);
      if (opcode == kPing) {
        send(kPong, payload);  // with the ping's payload (5.5.3)
      } else if (opcode == kClose) {
        try {
          send(kClose, std::string_view(payload).substr(0, 2));  // the server's status code back
        } catch (const std::exception&) {
        }
        throw Closed();
      } else if (opcode != kPong) {
        throw protocol_error("reserved control opcode " + std::to_string(opcode));
      }
      continue;
    }
    if (opcode == 0x0) {
      if (!in_message) throw protocol_error("continuation frame outside a message (5.4)");
    } else if (opcode == kText || opcode == kBinary) {
      if (in_message) throw protocol_error("a new message inside a fragmented one (5.4)");
      in_message = true;
      message.text = opcode == kText;
    } else {
      throw protocol_error("reserved data opcode " + std::to_string(opcode));
    }
    conn_.read_exact(static_cast<std::size_t>(length), message.data);
    if (fin) return message;
  }
}

void WebSocketClient::send(Opcode opcode, std::string_view payload) {
  const std::uint64_t n = payload.size();
  std::string frame;
  frame.reserve(payload.size() + 14);
  frame.push_back(static_cast<char>(0x80 | opcode));  // FIN: never fragmented
  if (n < 126) {
    frame.push_back(static_cast<char>(0x80 | n));
  } else if (n <= 0xFFFF) {
    frame.push_back(static_cast<char>(0x80 | 126));
    for (int i = 1; i >= 0; --i) frame.push_back(static_cast<char>((n >> (8 * i)) & 0xFF));
  } else {
    frame.push_back(static_cast<char>(0x80 | 127));
    for (int i = 7; i >= 0; --i) frame.push_back(static_cast<char>((n >> (8 * i)) & 0xFF));
  }
  std::array<std::uint8_t, 4> mask{};
  for (auto& b : mask) b = random_byte();
  frame.append(mask.begin(), mask.end());
  for (std::size_t i = 0; i < payload.size(); ++i) frame.push_back(static_cast<char>(byte_at(payload, i) ^ mask[i % 4]));
  std::lock_guard lock(write_mutex_);
  conn_.write(frame);
}

}  // namespace liod::test
