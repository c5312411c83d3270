#pragma once
// Live UDP reception for the LiDAR driver thread: one IPv4 datagram socket per port (MSOP, DIFOP),
// unicast or multicast, a large receive buffer, kernel receive timestamps (SO_TIMESTAMPNS, the
// moment the packet reached the socket, immune to the thread's scheduling delay) and batched
// reads with recvmmsg (one syscall per up to `batch` packets at the MSOP rate of ~1800 packets/s).

#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/uio.h>

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace liod::drivers {

/// Which sender's datagrams the LiDAR driver takes: the configured address, or else the first
/// sender of a datagram `lock_on` accepts (by IPv4 address, on every port: the sensor sends MSOP and
/// DIFOP from one address). Anyone else who reaches the port is refused and counted. Used on the
/// socket (UdpReceiver) and on a capture replayed (a tcpdump capture holds every sender).
class SourceFilter {
 public:
  using Predicate = std::function<bool(std::span<const std::uint8_t>)>;
  /// `fixed`: host-order address, 0 = none; `lock_on` unset: no lock (any sender).
  SourceFilter(std::uint32_t fixed, Predicate lock_on) : source_(fixed), lock_on_(std::move(lock_on)) {}
  /// Whether a datagram from `src_ip` passes (and takes the lock).
  [[nodiscard]] bool accept(std::uint32_t src_ip, std::span<const std::uint8_t> payload);
  [[nodiscard]] std::uint32_t source() const noexcept { return source_; }  ///< 0 = none yet
  [[nodiscard]] std::uint64_t refused() const noexcept { return refused_; }
  [[nodiscard]] std::uint32_t last_refused() const noexcept { return last_refused_; }  ///< its sender

 private:
  std::uint32_t source_;
  Predicate lock_on_;
  std::uint64_t refused_ = 0;
  std::uint32_t last_refused_ = 0;
};

struct UdpReceiverOptions {
  std::string bind_address = "0.0.0.0";
  std::vector<std::uint16_t> ports;     ///< one socket per port
  std::string multicast_group;          ///< "" = unicast
  std::string multicast_interface = "0.0.0.0";
  std::string source_address;           ///< "" = see lock_to_first_sender_of
  /// With no source_address, SourceFilter's lock: the first sender of a datagram this accepts is
  /// the only one taken from then on. Unset: any sender.
  SourceFilter::Predicate lock_to_first_sender_of;
  int receive_buffer_bytes = 16 * 1024 * 1024;
  int batch = 64;
};

struct ReceivedDatagram {
  std::int64_t kernel_time_ns = 0;  ///< CLOCK_REALTIME at reception (SO_TIMESTAMPNS); 0 if absent
  std::uint32_t src_ip = 0;         ///< host order
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
  std::span<const std::uint8_t> payload;  ///< valid during the callback only
};

struct UdpReceiverStats {
  std::uint64_t datagrams = 0;
  std::uint64_t bytes = 0;
  std::uint64_t filtered_source = 0;  ///< from an address other than source_address / the locked sender
  std::uint64_t truncated = 0;        ///< larger than the 2 KiB slot (not an RS-Helios packet)
  std::uint64_t kernel_drops = 0;     ///< SO_RXQ_OVFL: dropped by the kernel for a full buffer
};

class UdpReceiver {
 public:
  /// Opens, binds and (for multicast) joins. Throws std::runtime_error naming what failed.
  explicit UdpReceiver(UdpReceiverOptions options);
  ~UdpReceiver();
  UdpReceiver(const UdpReceiver&) = delete;
  UdpReceiver& operator=(const UdpReceiver&) = delete;

  using Handler = std::function<void(const ReceivedDatagram&)>;
  /// Waits up to `timeout_ms` for data, then delivers every datagram queued on every socket
  /// (batched). Returns the number delivered.
  std::size_t poll(int timeout_ms, const Handler& handler);

  const UdpReceiverStats& stats() const noexcept { return stats_; }
  const SourceFilter& source_filter() const noexcept { return filter_; }
  /// The receive buffer size the kernel granted (first socket).
  int granted_receive_buffer() const noexcept { return granted_rcvbuf_; }

 private:
  std::size_t drain(std::size_t index, const Handler& handler);
  UdpReceiverOptions options_;
  std::vector<int> fds_;
  std::vector<std::uint16_t> ports_;
  SourceFilter filter_;
  std::vector<std::uint8_t> buffers_;
  std::vector<std::uint8_t> controls_;
  UdpReceiverStats stats_;
  std::vector<std::uint32_t> last_ovfl_;
  std::vector<mmsghdr> msgs_;   // recvmmsg descriptors, kept to stay allocation-free
  std::vector<iovec> iov_;
  std::vector<sockaddr_in> from_;
  int granted_rcvbuf_ = 0;
};

/// Parses dotted IPv4 text into host order; throws std::runtime_error on bad text.
std::uint32_t parse_ipv4(const std::string& text);
/// Dotted text of a host-order IPv4 address.
std::string format_ipv4(std::uint32_t address);

}  // namespace liod::drivers
