#include "liod/daemon/pose_server.hpp"

#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace liod {
namespace {

std::runtime_error sys_error(const std::string& what) { return std::runtime_error(what + ": " + std::strerror(errno)); }

}  // namespace

PoseServer::PoseServer(const std::string& path, const PoseSocketConfig& config) : path_(path), config_(config) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof addr.sun_path) throw std::runtime_error("pose socket path '" + path + "': empty or too long");
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) throw sys_error("socket(AF_UNIX)");
  // A socket file left by a crashed run would make bind() fail; only a socket is ever removed.
  struct stat st{};
  if (::lstat(path.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) ::unlink(path.c_str());
  if (::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const auto e = sys_error("bind " + path);
    ::close(listen_fd_);
    throw e;
  }
  const auto mode = static_cast<mode_t>(std::stoul(config.mode, nullptr, 8));
  if (::chmod(path.c_str(), mode) != 0 || ::listen(listen_fd_, 16) != 0) {
    const auto e = sys_error("chmod/listen " + path);
    ::close(listen_fd_);
    ::unlink(path.c_str());
    throw e;
  }
  binary_.reserve(pose::kPoseMessageSize);
}

PoseServer::~PoseServer() {
  for (auto& c : clients_) ::close(c.fd);
  ::close(listen_fd_);
  ::unlink(path_.c_str());
}

void PoseServer::fill_pollfds(std::vector<pollfd>& fds) const {
  fds.push_back({listen_fd_, POLLIN, 0});
  for (const auto& c : clients_) {
    fds.push_back({c.fd, static_cast<short>(POLLIN | (c.sent < c.out.size() ? POLLOUT : 0)), 0});
  }
}

void PoseServer::handle(const std::vector<pollfd>& fds, std::size_t first) {
  if (first < fds.size() && (fds[first].revents & POLLIN) != 0) accept_clients();
  // Clients were listed after the listener in the same order; new ones (just accepted) and those
  // closed below are handled by walking backwards over the originally listed ones.
  const std::size_t listed = fds.size() - first - 1;
  for (std::size_t k = listed; k-- > 0;) {
    const pollfd& p = fds[first + 1 + k];
    if (k >= clients_.size() || clients_[k].fd != p.fd) continue;
    if ((p.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0 && (p.revents & POLLIN) == 0) {
      close_client(k);
      continue;
    }
    if ((p.revents & POLLIN) != 0) {
      read_requests(clients_[k]);
      if (clients_[k].fd < 0) {
        close_client(k);
        continue;
      }
    }
    if ((p.revents & POLLOUT) != 0) {
      flush(clients_[k]);
      if (clients_[k].fd < 0) close_client(k);
    }
  }
}

void PoseServer::accept_clients() {
  for (;;) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;
    if (clients_.size() >= static_cast<std::size_t>(config_.max_clients)) {
      ++stats_.rejected;
      ::close(fd);
      continue;
    }
    // The kernel's own send buffer adds to ours; keep it modest so "behind" is detected early.
    const int sndbuf = 64 * 1024;
    ::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf);
    Client c;
    c.fd = fd;
    c.last_progress = std::chrono::steady_clock::now();
    clients_.push_back(std::move(c));
    ++stats_.accepted;
    stats_.clients = clients_.size();
  }
}

void PoseServer::read_requests(Client& c) {
  char buf[256];
  for (;;) {
    const ssize_t n = ::recv(c.fd, buf, sizeof buf, MSG_DONTWAIT);
    if (n == 0) {  // orderly shutdown by the client
      ::close(c.fd);
      c.fd = -1;
      return;
    }
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return;
      ::close(c.fd);
      c.fd = -1;
      return;
    }
    c.requests.feed(std::string_view(buf, static_cast<std::size_t>(n)), c.mode);
  }
}

void PoseServer::queue(Client& c, const std::uint8_t* data, std::size_t n) {
  if (c.sent > 0 && c.sent == c.out.size()) {
    c.out.clear();
    c.sent = 0;
  }
  if (c.out.size() - c.sent + n > static_cast<std::size_t>(config_.client_buffer_bytes)) {
    ++stats_.skipped_messages;
    return;
  }
  if (c.out.size() == c.sent) c.last_progress = std::chrono::steady_clock::now();  // it was idle: start the stuck clock now
  c.out.insert(c.out.end(), data, data + n);
  ++stats_.sent_messages;
}

void PoseServer::flush(Client& c) {
  while (c.fd >= 0 && c.sent < c.out.size()) {
    const ssize_t n = ::send(c.fd, c.out.data() + c.sent, c.out.size() - c.sent, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n > 0) {
      c.sent += static_cast<std::size_t>(n);
      c.last_progress = std::chrono::steady_clock::now();
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) break;
    ::close(c.fd);  // EPIPE, ECONNRESET: gone
    c.fd = -1;
    return;
  }
  if (c.sent == c.out.size()) {
    c.out.clear();
    c.sent = 0;
  } else if (c.sent > 65536 && c.sent * 2 > c.out.size()) {
    c.out.erase(c.out.begin(), c.out.begin() + static_cast<std::ptrdiff_t>(c.sent));  // compact now and then
    c.sent = 0;
  }
}

void PoseServer::broadcast(const pose::PoseMessage& message) {
  if (clients_.empty()) return;
  pose::PoseMessage m = message;
  m.sequence = sequence_++;
  binary_.clear();
  pose::encode(m, binary_);
  std::string json;
  for (std::size_t i = clients_.size(); i-- > 0;) {
    Client& c = clients_[i];
    if (c.mode.scan_only && m.type != pose::MessageType::ScanPose) continue;
    if (c.mode.json) {
      if (json.empty()) json = pose::to_json_line(m);
      queue(c, reinterpret_cast<const std::uint8_t*>(json.data()), json.size());
    } else {
      queue(c, binary_.data(), binary_.size());
    }
    flush(c);
    if (c.fd < 0) close_client(i);
  }
}

void PoseServer::broadcast_health(const std::string& body) {
  if (clients_.empty()) return;
  binary_.clear();
  pose::encode_health(body, sequence_++, binary_);
  const std::string line = "{\"type\":\"health\",\"health\":" + body + "}\n";
  for (std::size_t i = clients_.size(); i-- > 0;) {
    Client& c = clients_[i];
    if (c.mode.json) queue(c, reinterpret_cast<const std::uint8_t*>(line.data()), line.size());
    else queue(c, binary_.data(), binary_.size());
    flush(c);
    if (c.fd < 0) close_client(i);
  }
}

void PoseServer::housekeeping() {
  const auto now = std::chrono::steady_clock::now();
  const auto limit = std::chrono::duration<double>(config_.stuck_timeout_s);
  for (std::size_t i = clients_.size(); i-- > 0;) {
    Client& c = clients_[i];
    if (c.sent < c.out.size() && now - c.last_progress > limit) {
      ++stats_.dropped_stuck;
      spdlog::warn("pose socket: dropping a client that read nothing for {:.1f} s", config_.stuck_timeout_s);
      ::close(c.fd);
      c.fd = -1;
      close_client(i);
    }
  }
}

void PoseServer::close_client(std::size_t i) {
  if (clients_[i].fd >= 0) ::close(clients_[i].fd);
  clients_.erase(clients_.begin() + static_cast<std::ptrdiff_t>(i));
  stats_.clients = clients_.size();
}

}  // namespace liod
