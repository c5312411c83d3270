#include "liod/drivers/can_imu.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cmath>
#include <cstring>
#include <ctime>
#include <stdexcept>

#include "liod/angles.hpp"
#include "liod/drivers/byte_order.hpp"

namespace liod::drivers {
namespace {

constexpr std::uint16_t kJ1939NotValid = 0xFB00;  // 0xFB00..0xFFFF: error / not available

int quantity_index(const std::string& q) {
  static const char* kNames[] = {"gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"};
  for (int i = 0; i < 6; ++i) {
    if (q == kNames[i]) return i;
  }
  return -1;
}

CanFrame j1939_frame(std::uint32_t pgn, std::uint8_t sa, const std::array<std::uint16_t, 3>& raw, std::int64_t t) {
  CanFrame f;
  f.extended = true;
  f.id = (3U << 26) | (pgn << 8) | sa;  // priority 3
  f.dlc = 8;
  for (int i = 0; i < 3; ++i) store_le16(&f.data[static_cast<std::size_t>(2 * i)], raw[static_cast<std::size_t>(i)]);
  f.data[6] = 0x00;  // status: all fully functional
  f.data[7] = 0x0A;  // latency 5 ms at 0.5 ms/bit
  f.time_ns = t;
  return f;
}

std::uint16_t to_raw(double value, double resolution, double offset) {
  const double r = std::round((value - offset) / resolution);
  return static_cast<std::uint16_t>(std::clamp(r, 0.0, 64255.0));
}

}  // namespace

std::uint32_t CanImuDecoder::pgn(std::uint32_t id) noexcept {
  const std::uint32_t pf = (id >> 16) & 0xFF;
  const std::uint32_t dp = (id >> 24) & 0x3;  // EDP + DP
  return pf >= 240 ? (dp << 16) | ((id >> 8) & 0xFFFF) : (dp << 16) | (pf << 8);
}

CanImuDecoder::CanImuDecoder(CanProfile profile, int j1939_source_address, std::vector<CanSignalConfig> table,
                             double max_pair_age_s)
    : profile_(profile), source_address_(j1939_source_address), table_(std::move(table)),
      max_pair_age_ns_(static_cast<std::int64_t>(max_pair_age_s * 1e9)) {}

std::optional<ImuSample> CanImuDecoder::feed(const CanFrame& f) {
  ++stats_.frames;
  return profile_ == CanProfile::kJ1939 ? feed_j1939(f) : feed_table(f);
}

std::optional<ImuSample> CanImuDecoder::feed_j1939(const CanFrame& f) {
  if (!f.extended || f.dlc < 6) return std::nullopt;
  if (source_address_ >= 0 && static_cast<int>(f.id & 0xFF) != source_address_) return std::nullopt;
  const std::uint32_t p = pgn(f.id);
  if (p != kPgnAngularRate && p != kPgnAcceleration) return std::nullopt;
  std::array<std::uint16_t, 3> raw{};
  for (std::size_t i = 0; i < 3; ++i) {
    raw[i] = load_le16(&f.data[2 * i]);
    if (raw[i] >= kJ1939NotValid) {
      ++stats_.not_available;
      return std::nullopt;
    }
  }
  if (p == kPgnAcceleration) {
    ++stats_.accel_frames;
    // bytes: lateral (y), longitudinal (x), vertical (z)
    auto v = [&](std::size_t i) { return raw[i] * 0.01 - 320.0; };
    accel_ = Eigen::Vector3d(v(1), v(0), v(2));
    accel_time_ns_ = f.time_ns;
    have_accel_ = true;
    return std::nullopt;
  }
  ++stats_.rate_frames;
  // bytes: pitch rate (about y), roll rate (about x), yaw rate (about z)
  auto w = [&](std::size_t i) { return (raw[i] / 128.0 - 250.0) * kDegToRad; };
  if (!have_accel_ || std::llabs(f.time_ns - accel_time_ns_) > max_pair_age_ns_) {
    ++stats_.unpaired;
    return std::nullopt;
  }
  ImuSample s;
  s.time = static_cast<double>(f.time_ns) * 1e-9;
  s.gyro = Eigen::Vector3d(w(1), w(0), w(2));
  s.accel = accel_;
  ++stats_.samples;
  return s;
}

std::optional<ImuSample> CanImuDecoder::feed_table(const CanFrame& f) {
  bool completes = false;
  bool matched = false;
  for (const auto& sig : table_) {
    if ((f.id & sig.id_mask) != (sig.can_id & sig.id_mask)) continue;
    const auto off = static_cast<std::size_t>(sig.byte_offset);
    const auto len = static_cast<std::size_t>(sig.length_bytes);
    if (off + len > f.dlc) continue;
    const std::uint8_t* p = &f.data[off];
    std::uint32_t u = 0;
    if (len == 1) u = p[0];
    else if (len == 2) u = load16(p, sig.big_endian);
    else u = load32(p, sig.big_endian);
    double raw = static_cast<double>(u);
    if (sig.is_signed) {
      if (len == 1) raw = static_cast<std::int8_t>(u);
      else if (len == 2) raw = static_cast<std::int16_t>(u);
      else raw = static_cast<std::int32_t>(u);
    }
    const int q = quantity_index(sig.quantity);
    if (q < 0) continue;
    const auto k = static_cast<std::size_t>(q);
    values_[k] = raw * sig.scale + sig.offset;
    value_times_ns_[k] = f.time_ns;
    received_[k] = true;
    matched = true;
    if (q == 0) completes = true;
  }
  if (!matched || !completes) return std::nullopt;
  for (std::size_t k = 0; k < values_.size(); ++k) {
    if (!received_[k] || f.time_ns - value_times_ns_[k] > max_pair_age_ns_) {
      ++stats_.stale_axes;
      return std::nullopt;
    }
  }
  ImuSample s;
  s.time = static_cast<double>(f.time_ns) * 1e-9;
  s.gyro = Eigen::Vector3d(values_[0], values_[1], values_[2]);
  s.accel = Eigen::Vector3d(values_[3], values_[4], values_[5]);
  ++stats_.samples;
  return s;
}

CanFrame from_socketcan(const can_frame& raw, std::int64_t time_ns) noexcept {
  CanFrame f;
  f.extended = (raw.can_id & CAN_EFF_FLAG) != 0;
  f.id = raw.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  f.dlc = std::min<std::uint8_t>(raw.can_dlc, 8);
  std::memcpy(f.data.data(), raw.data, 8);
  f.time_ns = time_ns;
  return f;
}

CanFrame make_j1939_rate_frame(const Eigen::Vector3d& w, std::uint8_t sa, std::int64_t t) {
  const double k = 1.0 / kDegToRad;
  return j1939_frame(CanImuDecoder::kPgnAngularRate, sa,
                     {to_raw(w.y() * k, 1.0 / 128.0, -250.0), to_raw(w.x() * k, 1.0 / 128.0, -250.0),
                      to_raw(w.z() * k, 1.0 / 128.0, -250.0)},
                     t);
}

CanFrame make_j1939_accel_frame(const Eigen::Vector3d& a, std::uint8_t sa, std::int64_t t) {
  return j1939_frame(CanImuDecoder::kPgnAcceleration, sa,
                     {to_raw(a.y(), 0.01, -320.0), to_raw(a.x(), 0.01, -320.0), to_raw(a.z(), 0.01, -320.0)}, t);
}

SocketCan::SocketCan(const std::string& interface) {
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC | SOCK_NONBLOCK, CAN_RAW);
  if (fd_ < 0) throw std::runtime_error(std::string("socket(PF_CAN): ") + std::strerror(errno));
  const unsigned index = ::if_nametoindex(interface.c_str());
  if (index == 0) {
    ::close(fd_);
    throw std::runtime_error("CAN interface '" + interface + "' not found");
  }
  const int one = 1;
  ::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one);
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd_);
    throw std::runtime_error("bind CAN " + interface + ": " + why);
  }
}

SocketCan::~SocketCan() { ::close(fd_); }

bool SocketCan::read(CanFrame& out, int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return false;
  can_frame frame{};
  iovec iov{&frame, sizeof frame};
  alignas(cmsghdr) char control[64];
  msghdr h{};
  h.msg_iov = &iov;
  h.msg_iovlen = 1;
  h.msg_control = control;
  h.msg_controllen = sizeof control;
  const ssize_t n = ::recvmsg(fd_, &h, MSG_DONTWAIT);
  if (n != static_cast<ssize_t>(sizeof frame)) return false;
  std::int64_t time_ns = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr; c = CMSG_NXTHDR(&h, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec ts{};
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      time_ns = static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
    }
  }
  if (time_ns == 0) {
    timespec ts{};
    ::clock_gettime(CLOCK_REALTIME, &ts);
    time_ns = static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
  }
  out = from_socketcan(frame, time_ns);
  return true;
}

void SocketCan::write(const CanFrame& f) {
  can_frame frame{};
  frame.can_id = f.id | (f.extended ? CAN_EFF_FLAG : 0U);
  frame.can_dlc = f.dlc;
  std::memcpy(frame.data, f.data.data(), 8);
  if (::write(fd_, &frame, sizeof frame) != static_cast<ssize_t>(sizeof frame)) {
    throw std::runtime_error(std::string("CAN write: ") + std::strerror(errno));
  }
}

}  // namespace liod::drivers
