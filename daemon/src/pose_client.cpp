#include "liod/daemon/pose_client.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace liod {

PoseClient::PoseClient(const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof addr.sun_path) throw std::runtime_error("pose socket path too long: " + path);
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  if (::connect(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error("cannot connect to " + path + ": " + why);
  }
}

PoseClient::~PoseClient() { disconnect(); }

void PoseClient::disconnect() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void PoseClient::request(const std::string& line) {
  if (fd_ < 0) return;
  const std::string l = line + "\n";
  if (::send(fd_, l.data(), l.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(l.size())) disconnect();
}

bool PoseClient::fill(std::chrono::steady_clock::time_point deadline) {
  if (fd_ < 0) return false;
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
  pollfd p{fd_, POLLIN, 0};
  if (::poll(&p, 1, static_cast<int>(std::max<std::int64_t>(0, left.count()))) <= 0) return false;
  if (start_ > 0 && start_ * 2 > buffer_.size()) {
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(start_));
    start_ = 0;
  }
  std::uint8_t chunk[16384];
  const ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
  if (n <= 0) {
    if (n < 0 && errno == EINTR) return true;
    disconnect();
    return false;
  }
  buffer_.insert(buffer_.end(), chunk, chunk + n);
  return true;
}

bool PoseClient::read(pose::Message& out, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    std::size_t used = 0;
    const auto status = pose::decode(std::span(buffer_).subspan(start_), out, used);
    if (status == pose::DecodeStatus::Ok) {
      start_ += used;
      return true;
    }
    if (status == pose::DecodeStatus::Invalid) {
      disconnect();
      return false;
    }
    if (!fill(deadline)) return false;
  }
}

bool PoseClient::read_line(std::string& line, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    for (std::size_t i = start_; i < buffer_.size(); ++i) {
      if (buffer_[i] == '\n') {
        line.assign(reinterpret_cast<const char*>(buffer_.data() + start_), i - start_);
        start_ = i + 1;
        return true;
      }
    }
    if (!fill(deadline)) return false;
  }
}

}  // namespace liod
