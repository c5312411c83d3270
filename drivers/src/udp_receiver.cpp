#include "liod/drivers/udp_receiver.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace liod::drivers {
namespace {

constexpr std::size_t kSlot = 2048;     // an RS-Helios packet is 1248 bytes
constexpr std::size_t kControl = 128;   // room for SCM_TIMESTAMPNS + SO_RXQ_OVFL

std::runtime_error sys_error(const std::string& what) { return std::runtime_error(what + ": " + std::strerror(errno)); }

}  // namespace

std::uint32_t parse_ipv4(const std::string& text) {
  in_addr a{};
  if (::inet_pton(AF_INET, text.c_str(), &a) != 1) throw std::runtime_error("not an IPv4 address: '" + text + "'");
  return ntohl(a.s_addr);
}

std::string format_ipv4(std::uint32_t address) {
  return std::to_string(address >> 24) + "." + std::to_string((address >> 16) & 0xFF) + "." +
         std::to_string((address >> 8) & 0xFF) + "." + std::to_string(address & 0xFF);
}

UdpReceiver::UdpReceiver(UdpReceiverOptions options)
    : options_(std::move(options)),
      filter_(options_.source_address.empty() ? 0 : parse_ipv4(options_.source_address),
              options_.lock_to_first_sender_of) {
  const std::uint32_t bind_ip = options_.multicast_group.empty() ? parse_ipv4(options_.bind_address) : 0;
  for (const std::uint16_t port : options_.ports) {
    const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) throw sys_error("socket(UDP)");
    fds_.push_back(fd);
    ports_.push_back(port);
    const int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    // SO_RCVBUFFORCE passes net.core.rmem_max with CAP_NET_ADMIN; without it SO_RCVBUF is capped.
    int size = options_.receive_buffer_bytes;
    if (::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &size, sizeof size) != 0) {
      ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &size, sizeof size);
    }
    socklen_t len = sizeof size;
    if (granted_rcvbuf_ == 0 && ::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &size, &len) == 0) granted_rcvbuf_ = size;
    if (::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one) != 0) throw sys_error("SO_TIMESTAMPNS");
    ::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one);  // kernel drop counter, best effort
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(port);
    // For multicast, bind the group (or any) address so only the group's traffic arrives.
    addr.sin_addr.s_addr = htonl(options_.multicast_group.empty() ? bind_ip : parse_ipv4(options_.multicast_group));
    if (::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
      throw sys_error("bind UDP port " + std::to_string(port));
    }
    if (!options_.multicast_group.empty()) {
      ip_mreq mreq{};
      mreq.imr_multiaddr.s_addr = htonl(parse_ipv4(options_.multicast_group));
      mreq.imr_interface.s_addr = htonl(parse_ipv4(options_.multicast_interface));
      if (::setsockopt(fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq) != 0) {
        throw sys_error("join multicast group " + options_.multicast_group);
      }
    }
  }
  const auto batch = static_cast<std::size_t>(options_.batch < 1 ? 1 : options_.batch);
  buffers_.resize(batch * kSlot);
  controls_.resize(batch * kControl);
  last_ovfl_.assign(fds_.size(), 0);
  msgs_.resize(batch);
  iov_.resize(batch);
  from_.resize(batch);
}

UdpReceiver::~UdpReceiver() {
  for (const int fd : fds_) ::close(fd);
}

std::size_t UdpReceiver::poll(int timeout_ms, const Handler& handler) {
  std::vector<pollfd> p;
  p.reserve(fds_.size());
  for (const int fd : fds_) p.push_back({fd, POLLIN, 0});
  if (::poll(p.data(), p.size(), timeout_ms) <= 0) return 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if ((p[i].revents & POLLIN) != 0) n += drain(i, handler);
  }
  return n;
}

bool SourceFilter::accept(std::uint32_t src_ip, std::span<const std::uint8_t> payload) {
  if (source_ == 0 && lock_on_ && lock_on_(payload)) source_ = src_ip;
  if (source_ == 0 || src_ip == source_) return true;
  ++refused_;
  last_refused_ = src_ip;
  return false;
}

std::size_t UdpReceiver::drain(std::size_t index, const Handler& handler) {
  const std::size_t batch = buffers_.size() / kSlot;
  auto& msgs = msgs_;
  auto& iov = iov_;
  auto& from = from_;
  std::size_t total = 0;
  for (;;) {
    for (std::size_t i = 0; i < batch; ++i) {
      iov[i] = {buffers_.data() + i * kSlot, kSlot};
      msgs[i] = {};
      msgs[i].msg_hdr.msg_iov = &iov[i];
      msgs[i].msg_hdr.msg_iovlen = 1;
      msgs[i].msg_hdr.msg_name = &from[i];
      msgs[i].msg_hdr.msg_namelen = sizeof(sockaddr_in);
      msgs[i].msg_hdr.msg_control = controls_.data() + i * kControl;
      msgs[i].msg_hdr.msg_controllen = kControl;
    }
    const int got = ::recvmmsg(fds_[index], msgs.data(), static_cast<unsigned>(batch), MSG_DONTWAIT, nullptr);
    if (got <= 0) break;
    for (int i = 0; i < got; ++i) {
      const msghdr& h = msgs[static_cast<std::size_t>(i)].msg_hdr;
      ReceivedDatagram d;
      for (cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr; c = CMSG_NXTHDR(const_cast<msghdr*>(&h), c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
          timespec ts{};
          std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
          d.kernel_time_ns = static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
        } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
          std::uint32_t ovfl = 0;
          std::memcpy(&ovfl, CMSG_DATA(c), sizeof ovfl);
          if (ovfl > last_ovfl_[index]) stats_.kernel_drops += ovfl - last_ovfl_[index];
          last_ovfl_[index] = ovfl;
        }
      }
      const auto& src = from[static_cast<std::size_t>(i)];
      d.src_ip = ntohl(src.sin_addr.s_addr);
      d.src_port = ntohs(src.sin_port);
      d.dst_port = ports_[index];
      const std::size_t len = msgs[static_cast<std::size_t>(i)].msg_len;
      if ((h.msg_flags & MSG_TRUNC) != 0) {
        ++stats_.truncated;
        continue;
      }
      d.payload = std::span<const std::uint8_t>(buffers_.data() + static_cast<std::size_t>(i) * kSlot, len);
      if (!filter_.accept(d.src_ip, d.payload)) {
        stats_.filtered_source = filter_.refused();
        continue;
      }
      ++stats_.datagrams;
      stats_.bytes += len;
      handler(d);
      ++total;
    }
    if (static_cast<std::size_t>(got) < batch) break;
  }
  return total;
}

}  // namespace liod::drivers
